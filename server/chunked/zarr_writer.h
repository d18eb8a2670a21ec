// Writing OME-Zarr (NGFF 0.4, zarr v2): one array per pyramid level, chunks keyed "z/y/x".
#pragma once

#include <cstdint>
#include <filesystem>

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

// Writes `volume` (with voxels) in its source type to the folder `out`, which must not exist: it
// is written as `out`.partial and renamed when whole, so no half-written pyramid is ever read.
// Throws VolumeError (out exists, a write fails) or std::invalid_argument (a chunk edge < 1).
ZarrWriteReport write_ome_zarr(const Volume& volume, const std::filesystem::path& out, const ZarrWriteOptions& options);

}  // namespace peakcast::chunked
