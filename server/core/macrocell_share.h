// Distributed rendering (docs/distributed.md): the whole volume's macrocell grids built from its
// bricks, so that a rank holding one brick walks the same cells as one process holding the
// volume (space skipping's leaps, adaptive multipliers, where a virtual-sample run ends). Each
// brick adds what its counted voxels (distributed::counted_box: every voxel counted by exactly one
// brick) contribute to each cell's footprint; the shares combine by min, max and sums (an
// MPI_Allreduce, or add_share in one process), and grid_from_share finishes the grid
// build_macrocells would have built from the whole volume: the same min/max, the standard
// deviation up to the order of its sums.
#pragma once

#include <vector>

#include "core/macrocells.h"
#include "core/volume.h"

namespace peakcast {

struct MacrocellShare {
  int cell = 8;
  Dims grid{0, 0, 0};
  FilterSupport support = FilterSupport::Trilinear;
  // Per cell (MacrocellGrid::index): the footprint's extremes over this share's voxels
  // (+inf/-inf where it has none, physical values) and its own voxels' count, sum, sum of squares.
  std::vector<float> min, max;
  std::vector<double> own, sum, sum2;
};

// A brick's share. `brick` was read as a region of a volume of `whole` dims (region_lo: its
// first voxel there); it counts the voxels [count_lo, count_hi) in its own coordinates. `cell`:
// the edge in voxels, 0 for default_cell_size(whole). build_macrocells is the share of a whole
// volume counting all of it. std::invalid_argument when the counted box is not inside the brick
// or the whole volume.
MacrocellShare macrocell_share(const Volume& brick, const Dims& whole, const Dims& count_lo, const Dims& count_hi,
                               FilterSupport support, int cell = 0);
// The same with the brick's first voxel given (build_macrocells: a whole volume at 0).
MacrocellShare macrocell_share_at(const Volume& brick, const Dims& region_lo, const Dims& whole, const Dims& count_lo,
                                  const Dims& count_hi, FilterSupport support, int cell = 0);
// The same added into `into` (a share of the same grid, or an empty one), without a second
// whole grid: what add_share of macrocell_share_at's result gives, bit for bit.
void add_macrocell_share_at(MacrocellShare& into, const Volume& brick, const Dims& region_lo, const Dims& whole,
                            const Dims& count_lo, const Dims& count_hi, FilterSupport support, int cell = 0);
// Both supports' shares at once, in one pass over the voxels (an out-of-core still's statistics).
void add_macrocell_shares_at(MacrocellShare& trilinear, MacrocellShare& tricubic, const Volume& brick,
                             const Dims& region_lo, const Dims& whole, const Dims& count_lo, const Dims& count_hi,
                             int cell = 0);
// Adds `other` (of the same grid) into `into`: min of the minima, max of the maxima, sums.
void add_share(MacrocellShare& into, const MacrocellShare& other);
// The grid once every brick's share has been added. std::invalid_argument when a cell got no voxels.
MacrocellGrid grid_from_share(const MacrocellShare& share);

}  // namespace peakcast
