// Out-of-core rendering: the brick path of a distributed render taken in time by one process
// (docs/chunked-volumes.md). The volume is cut into the fewest k-d bricks that fit a host memory
// budget; the whole volume's statistics are reduced from the bricks as the ranks reduce them, and
// a still is drawn brick after brick, front to back, each layer composited "over" as it comes,
// the next brick read while this one renders. Any format with region reads works: OME-Zarr and
// Neuroglancer precomputed read only the chunks a brick meets.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "core/image.h"
#include "core/macrocells.h"
#include "core/scene.h"
#include "core/volume_io.h"
#include "distributed/kd_split.h"
#include "render/renderer.h"

namespace peakcast::distributed {

// The fewest bricks whose largest read box (ghosts included) holds at most `budget_bytes` of
// voxels; `holding` bricks are held at once (2: one rendering, the next being read). Throws
// std::invalid_argument when even one voxel plane per brick would not fit.
int bricks_for_budget(const Index3& dims, int ghost, size_t voxel_bytes, int64_t budget_bytes, int holding);

struct SequenceStatistics {
  VolumeBox box;           // dims, spacing, origin, the whole volume's range and histogram
  VolumeMacrocells cells;  // the whole volume's grids, from the bricks' shares
  SourceType source = SourceType::U8;
  int64_t nonfinite = 0;   // NaN/Inf voxels, replaced by the finite extremes
  int bricks = 0;
  int64_t bytes_read = 0;  // voxel bytes of both passes
  double ms = 0.0;
};

// The bricks of a sequence take 90% of budget_bytes; the rest is for decoding chunks, the image
// layers and the grids. Statistics: integer volumes in one pass over the bricks (each stored
// value counted: range and histogram exactly, and the macrocell shares); float volumes in two,
// the finite range, then the histogram and the macrocell grids over that range. `base` carries level, time point, channel
// and the non-finite policy (Refuse throws VolumeError as a whole read would).
SequenceStatistics sequence_statistics(const std::string& path, const LoadOptions& base, int64_t budget_bytes,
                                       const std::function<void(double)>& progress = {});

struct SequenceResult {
  Image image;
  int bricks = 0, ghost = 0;
  int64_t bytes_read = 0;
  int64_t largest_brick_bytes = 0;
  double read_ms = 0.0, render_ms = 0.0;  // reading overlaps rendering: the two add up to more than the wall time
};

// `scene` (resolved against stats.box) drawn by bricks with `renderer`, holding at most two
// bricks (90% of budget_bytes in all). progress: the share of bricks composited.
SequenceResult render_sequence(render::Renderer& renderer, const std::string& path, const LoadOptions& base,
                               const SequenceStatistics& stats, const ResolvedScene& scene, int64_t budget_bytes,
                               const std::function<void(double)>& progress = {});

}  // namespace peakcast::distributed
