// Macrocell min/max grid for empty-space skipping (Knoll §6.1, Lee §3.2).
//
// Cell (a, b, c) covers the sample positions [c*e, (c+1)*e] in voxel coordinates (the last cell
// is clipped at n-1). Its [min, max] covers every voxel that a sample inside it can read:
// trilinear reads voxels floor(x)..floor(x)+1, so the range is the cell's voxels plus one;
// the cubic B-spline reads floor(x)-1..floor(x)+2, so one more before and two after.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/volume.h"

namespace peakcast {

enum class FilterSupport { Trilinear, Tricubic };

struct MacrocellGrid {
  int cell = 8;        // edge length in voxels (same on every axis)
  Dims grid{0, 0, 0};  // cells per axis
  FilterSupport support = FilterSupport::Trilinear;
  std::vector<float> min, max;  // physical values, index a + grid[0] * (b + grid[1] * c)
  std::vector<float> stddev;    // over the cell's own voxels [c*e, (c+1)*e)
  double build_ms = 0.0;

  size_t index(int64_t a, int64_t b, int64_t c) const { return size_t(a + grid[0] * (b + grid[1] * c)); }
  size_t size() const { return min.size(); }
  std::string to_string() const;
};

// Smallest edge >= 8 voxels that keeps the grid at most 64 cells per axis.
int default_cell_size(const Dims& dims);
int64_t cells_along(int64_t n, int cell);

MacrocellGrid build_macrocells(const Volume& volume, int cell = 0, FilterSupport support = FilterSupport::Trilinear);

// The grids a volume's renders use (default cell size), built once per volume off the render
// thread: the server builds them on the loader pool with the volume (VolumeEntry) and hands
// them to GlVolume, so a session switching volumes does not stall every other session.
struct VolumeMacrocells {
  std::shared_ptr<const MacrocellGrid> trilinear, tricubic;
  double build_ms = 0.0;  // both grids, wall time
};
VolumeMacrocells build_volume_macrocells(const Volume& volume);
// Each cell's [min, max] widened to the union over the cells within `ring` cells of it (a cube
// of 2 ring + 1 cells per axis): the values a Catmull-Rom window reaching `ring` cells away can
// read (virtual samples, Lee §3.2). ring 0 returns the grid unchanged.
MacrocellGrid dilate_ranges(const MacrocellGrid& g, int ring);
// The dims a volume's grids cover: its own, or for a region read (a distributed rendering's
// brick) the whole volume's (core/macrocell_share.h: a brick walks the whole volume's cells).
Dims grid_dims(const Volume& volume);
// Throws std::invalid_argument unless `g` is a default-cell grid of grid_dims(volume) with the
// given support (a grid of another volume would skip visible cells).
void check_macrocells(const MacrocellGrid& g, const Volume& volume, FilterSupport support);

}  // namespace peakcast
