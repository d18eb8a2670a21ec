#include "core/macrocells.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/macrocell_share.h"
#include "core/parallel.h"

namespace peakcast {

int default_cell_size(const Dims& dims) {
  int cell = 8;
  for (int a = 0; a < 3; ++a) cell = std::max<int>(cell, int((dims[a] - 1 + 63) / 64));
  return cell;
}

int64_t cells_along(int64_t n, int cell) { return std::max<int64_t>(1, (n - 1 + cell - 1) / cell); }

MacrocellGrid build_macrocells(const Volume& v, int cell, FilterSupport support) {
  const auto t0 = std::chrono::steady_clock::now();
  const Dims n = v.dims();
  MacrocellGrid g = grid_from_share(macrocell_share_at(v, Dims{0, 0, 0}, n, Dims{0, 0, 0}, n, support, cell));
  g.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return g;
}

// Two passes, one per grid. A single pass over the tricubic windows serving both grids was
// tried and was no faster on the em volume (500-560 ms against 222 + 284 ms): the
// build is bound by reading rows across planes, not by the passes.
VolumeMacrocells build_volume_macrocells(const Volume& v) {
  const auto t0 = std::chrono::steady_clock::now();
  VolumeMacrocells m;
  m.trilinear = std::make_shared<const MacrocellGrid>(build_macrocells(v, 0, FilterSupport::Trilinear));
  m.tricubic = std::make_shared<const MacrocellGrid>(build_macrocells(v, 0, FilterSupport::Tricubic));
  m.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return m;
}

Dims grid_dims(const Volume& v) { return v.source_dims == Dims{0, 0, 0} ? v.dims() : v.source_dims; }

void check_macrocells(const MacrocellGrid& g, const Volume& v, FilterSupport support) {
  const Dims dims = grid_dims(v);
  MacrocellGrid want;
  want.cell = default_cell_size(dims);
  for (int a = 0; a < 3; ++a) want.grid[a] = cells_along(dims[a], want.cell);
  want.support = support;
  if (g.cell != want.cell || g.grid != want.grid || g.support != support ||
      g.size() != size_t(want.grid[0] * want.grid[1] * want.grid[2]))
    throw std::invalid_argument("macrocells " + g.to_string() + " do not fit the " + std::to_string(dims[0]) + "x" +
                                std::to_string(dims[1]) + "x" + std::to_string(dims[2]) + " volume (want " +
                                want.to_string() + ")");
}

std::string MacrocellGrid::to_string() const {
  std::ostringstream s;
  s << "Macrocells{" << grid[0] << "x" << grid[1] << "x" << grid[2] << " cells of " << cell << " voxels, "
    << (support == FilterSupport::Tricubic ? "tricubic" : "trilinear") << " support}";
  return s.str();
}

MacrocellGrid dilate_ranges(const MacrocellGrid& g, int ring) {
  MacrocellGrid out = g;
  if (ring <= 0) return out;
  // Separable: the min/max over a window along each axis in turn.
  for (int axis = 0; axis < 3; ++axis) {
    const std::vector<float> lo = out.min, hi = out.max;
    for (int64_t c = 0; c < g.grid[2]; ++c)
      for (int64_t b = 0; b < g.grid[1]; ++b)
        for (int64_t a = 0; a < g.grid[0]; ++a) {
          int64_t at[3] = {a, b, c};
          const int64_t from = std::max<int64_t>(0, at[axis] - ring), to = std::min(g.grid[axis] - 1, at[axis] + ring);
          const size_t i = g.index(a, b, c);
          for (int64_t x = from; x <= to; ++x) {
            at[axis] = x;
            const size_t j = g.index(at[0], at[1], at[2]);
            out.min[i] = std::min(out.min[i], lo[j]);
            out.max[i] = std::max(out.max[i], hi[j]);
          }
        }
  }
  return out;
}

}  // namespace peakcast
