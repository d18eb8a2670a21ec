// How many tables of per-value counts Volume::box_value_counts fills at once: one per thread, at
// most four for 16-bit voxels (65536 counts, 512 KiB a table), whatever the cores. An
// out-of-core still's statistics count them in the memory budget (distributed/brick_sequence.cpp).
#pragma once

#include <algorithm>

#include "core/parallel.h"
#include "core/volume.h"

namespace peakcast {

inline int value_count_tables(VoxelType t) {
  return t == VoxelType::U16 ? std::min(hardware_threads(), 4) : hardware_threads();
}

}  // namespace peakcast
