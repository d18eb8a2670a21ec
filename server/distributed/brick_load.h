// One rank's brick of a volume file for distributed rendering, read by every rank in
// the same call (MPI collectives): the k-d split, the brick with its ghost voxels, and, on the
// first read, the whole volume's statistics reduced from the bricks, so that no rank, the one
// that serves included, ever holds the whole volume: value range (NaN/Inf replaced by the whole
// volume's finite extremes first, as one process does), the histogram (each voxel counted by
// exactly one brick) and the non-finite count.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/macrocells.h"
#include "core/scene.h"
#include "core/volume.h"
#include "distributed/kd_split.h"

namespace peakcast::distributed {

// What every rank reads: the payload rank 0 broadcasts.
struct BrickLoadRequest {
  std::string path;
  int64_t time_point = 0;  // a time series' point (every rank reads its brick of that one)
  int ghost = 0;
  // Known from an earlier read (a re-read with wider ghosts): no statistics are reduced.
  bool have_range = false;
  double lo = 0.0, hi = 0.0;
  bool refuse_nonfinite = false;  // NonFinitePolicy::Refuse: a NaN/Inf voxel on any rank refuses
  nlohmann::json to_json() const;
  static BrickLoadRequest from_json(const nlohmann::json& j);
};

struct BrickRead {
  VolumeBox box;  // the whole volume's box and value range
  Index3 dims{};
  int ghost = 0;
  KdSplit split;
  Brick mine;
  std::shared_ptr<Volume> voxels;  // the brick's (with the whole volume's histogram); null when refused
  VolumeMacrocells cells;          // the whole volume's grids, reduced from the bricks
  // The whole volume's (first reads only): histogram, non-finite count, the largest brick's
  // bytes. refused: a NaN/Inf voxel under refuse_nonfinite (every rank knows).
  std::vector<uint64_t> histogram, border_histogram;  // (border: Volume::border_histogram)
  int64_t nonfinite = 0;
  int64_t max_brick_bytes = 0;
  bool refused = false;
  // A rank could not read its part: every rank returns this alike, with no voxels. error: this
  // rank's reason, or on the others which rank failed.
  bool failed = false;
  std::string error;
  double statistics_ms = 0.0;  // the reductions after the reads
};

// The file's header without its voxels: a one-voxel region read (of time point `time_point`),
// whose source_dims are the whole volume's dims (throws VolumeError, e.g. for a TIFF stack, which
// has no regions, or a time point the file does not hold).
Volume read_head(const std::string& path, int64_t time_point = 0);

// Every rank, collectively, in the same order whatever happens: a read that fails on any rank
// makes every rank return `failed` (the job goes on); the statistics follow only for a first
// read (no range in the request).
BrickRead read_brick(const BrickLoadRequest& request);

}  // namespace peakcast::distributed
