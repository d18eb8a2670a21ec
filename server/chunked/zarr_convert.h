// `peakcast convert IN OUT.zarr` for an input larger than memory: level 0 is read from IN by slabs
// of whole z-planes (region reads: raw data reads only the slab's rows), each level above from the
// level below it as written, so no level is ever whole in memory. The pyramid equals the one
// write_ome_zarr writes from the whole volume, byte for byte (the same 2x2x2 means, NaN and -Inf
// replaced by the finite minimum and +Inf by the maximum, as a whole read replaces them).
#pragma once

#include <cstdint>
#include <filesystem>

#include "chunked/zarr_writer.h"
#include "core/volume_io.h"

namespace peakcast::chunked {

struct SlabConvertReport {
  ZarrWriteReport zarr;
  VolumeHeader header;      // level 0's (time_points: those written)
  int64_t slab_planes = 0;  // z-planes per slab read from IN
  int64_t slab_bytes = 0;   // the largest slab's voxel bytes
  int passes = 1;           // reads of IN (2 for a float volume: its finite range first)
};

// The voxel bytes of `in` from its header alone (a one-voxel read), and that header. Throws
// RegionNotReadable for a format read only whole (a TIFF stack).
int64_t source_voxel_bytes(const std::filesystem::path& in, const LoadOptions& select, VolumeHeader* header = nullptr);

// Host memory a whole read and write_ome_zarr take for `voxel_bytes`: the volume, the writer's
// copy of it and the pyramid's coarser levels (1/7 more), rounded up.
inline int64_t whole_convert_bytes(int64_t voxel_bytes) { return voxel_bytes / 4 * 9; }

// Writes `in` as OME-Zarr at `out`, reading at most two slabs at a time whose voxels fit
// `budget_bytes` together (at least one chunk edge of planes each) from a format with region reads
// (raw, NRRD, MetaImage, OME-Zarr, precomputed); a TIFF stack is read a whole time point at a time.
// `series`: every time point of `in` (a t axis; select.time_point is ignored), else the one
// selected. Throws VolumeError (unreadable input, `out` exists) or std::invalid_argument
// (options).
SlabConvertReport convert_to_ome_zarr_by_slabs(const std::filesystem::path& in, const std::filesystem::path& out,
                                               const LoadOptions& select, const ZarrWriteOptions& options,
                                               int64_t budget_bytes, bool series = false);

}  // namespace peakcast::chunked
