// Which macrocells can contribute under the current TF: a cell is empty when the
// TF's opacity is zero over its whole [min, max]. Rebuilt on every TF edit: a range-max query
// per cell over the baked 8192-entry opacity table (sparse table, O(1) per cell).
#pragma once

#include <cstdint>
#include <vector>

#include "core/macrocells.h"
#include "core/transfer_function.h"

namespace peakcast {

struct Occupancy {
  std::vector<uint8_t> occupied;  // per cell, MacrocellGrid order
  // Per cell, the Chebyshev distance in cells to the nearest occupied cell (0: occupied; cells
  // beyond the grid count as empty), at most kMaxEmptyDistance. What the GL traversal reads: a
  // ray in a cell at distance d leaps out of the cube of 2d - 1 cells around it, all empty.
  std::vector<uint8_t> distance;
  int64_t empty_cells = 0;
  double build_ms = 0.0;
};

constexpr int kMaxEmptyDistance = 255;

// `lo`, `hi`: the TF table's domain (the volume's value range). The table is sampled with
// linear filtering, so each cell's range is widened by one table entry on each side.
// With peak finding, a cell whose range holds a peak value is occupied too (a Dirac-like peak is
// narrower than a table entry, so the opacity table alone would call it empty).
// `overshoot`: each cell's [m, M] is widened by overshoot * (M - m) on both sides first; virtual
// samples use 1/8, the most a Catmull-Rom segment overshoots its samples (Lee et al. eq. 8).
constexpr double kCatmullRomOvershoot = 1.0 / 8.0;
Occupancy classify_cells(const MacrocellGrid& grid, const TransferFunction& tf, double lo, double hi,
                         const std::vector<double>& peak_values = {}, int table_size = TransferFunction::kTableSize,
                         double overshoot = 0.0);

// The `distance` field of `occupied` on `grid` (separable: exact Chebyshev distance per axis).
std::vector<uint8_t> empty_space_distance(const Dims& grid, const std::vector<uint8_t>& occupied);

}  // namespace peakcast
