// Writing OME-Zarr (NGFF 0.4, zarr v2): one array per pyramid level, chunks keyed "z/y/x" (a time
// series: axes t, z, y, x, chunks of one time point keyed "t/z/y/x").
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "chunked/chunk_codec.h"
#include "core/volume.h"

namespace peakcast::chunked {

struct ZarrWriteOptions {
  int64_t chunk = 128;  // chunk edge, voxels
  // Levels of 2x2x2 means (sizes rounded up) until a level fits in one chunk; false: level 0 only.
  bool pyramid = false;
  CompressorSpec compressor = compressor_by_name("blosc");
};

struct ZarrWriteReport {
  int levels = 0;
  int64_t chunks = 0, bytes = 0;  // chunk files written and their bytes
};

// A level's box [lo, lo + box) of voxels at time point t to fill (t is 0 unless the header's
// time_points > 1): box voxels, x fastest, in the source type (little-endian; signed types as
// signed). Called from several threads at once, time point by time point, each in z order.
using ChunkFill = std::function<void(int level, int64_t t, const Dims& lo, const Dims& box, uint8_t* out)>;

// A pyramid written chunk by chunk from `fill`, never whole in memory: level k has dims
// ceil(dims / 2^k), spacing 2^k times level 0's and its first voxel at the centre of level 0's
// first 2^k block. `levels` levels (1: no pyramid). level0.time_points > 1: a series, every
// level holding each time point. Same folder rules as write_ome_zarr.
ZarrWriteReport write_ome_zarr_levels(const std::filesystem::path& out, const VolumeHeader& level0, int levels,
                                      const std::string& name, const ZarrWriteOptions& options, const ChunkFill& fill);

// Levels a pyramid of `dims` gets: halved until the largest axis fits `chunk`.
int pyramid_levels(const Dims& dims, int64_t chunk);

// Where write_ome_zarr_levels writes `out` until it is whole: level k lies in partial_path(out)/k,
// complete (its .zarray and chunks) before level k + 1's first fill, and from then on the folder
// reads as an OME-Zarr of levels 0..k (its .zattrs rewritten as each level completes).
std::filesystem::path partial_path(const std::filesystem::path& out);

// The next level's voxels: the 2x2x2 means of `in` (dims `in_dims`, a volume's storage type),
// sizes rounded up (a mean over the voxels there are at an odd edge), integers rounded.
std::vector<uint8_t> halve_voxels(VoxelType type, const Dims& in_dims, const uint8_t* in, Dims& out_dims);

// Un-shifts n of a Volume's stored voxels back to the source type (int8 - 128, int16 - 32768).
void unshift_voxels(uint8_t* p, size_t n, SourceType source);

// Writes `volume` (with voxels) in its source type to the folder `out`, which must not exist: it
// is written as `out`.partial-PID and renamed when whole, so no half-written pyramid is ever read.
// Throws VolumeError (out exists, a write fails) or std::invalid_argument (a chunk edge < 1).
ZarrWriteReport write_ome_zarr(const Volume& volume, const std::filesystem::path& out, const ZarrWriteOptions& options);

}  // namespace peakcast::chunked
