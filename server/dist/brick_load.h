// One rank's brick of a volume file for distributed rendering (issue 16), read by every rank in
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

#include "core/scene.h"
#include "core/volume.h"
#include "dist/kd_split.h"

namespace peakcast::dist {

// What every rank reads: the payload rank 0 broadcasts.
struct BrickLoadRequest {
  std::string path;
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
  std::shared_ptr<Volume> voxels;  // the brick's; null when refused
  // The whole volume's, on rank 0 (first reads only): histogram, non-finite count, the largest
  // brick's bytes. refused: a NaN/Inf voxel under refuse_nonfinite (every rank knows).
  std::vector<uint64_t> histogram;
  int64_t nonfinite = 0;
  int64_t max_brick_bytes = 0;
  bool refused = false;
};

// Every rank, collectively. Errors (a file that cannot be read) throw on the rank that met
// them: the caller ends the job, since the others wait in a collective.
BrickRead read_brick(const BrickLoadRequest& request);

}  // namespace peakcast::dist
