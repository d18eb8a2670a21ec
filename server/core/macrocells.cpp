#include "core/macrocells.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/parallel.h"

namespace peakcast {

int default_cell_size(const Dims& dims) {
  int cell = 8;
  for (int a = 0; a < 3; ++a) cell = std::max<int>(cell, int((dims[a] - 1 + 63) / 64));
  return cell;
}

int64_t cells_along(int64_t n, int cell) { return std::max<int64_t>(1, (n - 1 + cell - 1) / cell); }

namespace {

// One cell's statistics, reading rows of the voxel type directly (a type switch per voxel
// made the em volume's grids take over a second). lo/hi: the filter's voxels; own_*: the
// cell's own voxels for the standard deviation.
struct CellStats {
  double mn, mx, sum = 0, sum2 = 0;
  int64_t own = 0;
};

template <typename T>
CellStats cell_stats(const T* data, const Dims& n, const int64_t lo[3], const int64_t hi[3], const int64_t own_lo[3],
                     const int64_t own_hi[3]) {
  T mn = data[size_t(lo[0] + n[0] * (lo[1] + n[1] * lo[2]))], mx = mn;
  CellStats st;
  for (int64_t k = lo[2]; k <= hi[2]; ++k)
    for (int64_t j = lo[1]; j <= hi[1]; ++j) {
      const T* row = data + size_t(n[0] * (j + n[1] * k));
      for (int64_t i = lo[0]; i <= hi[0]; ++i) {
        mn = std::min(mn, row[i]);
        mx = std::max(mx, row[i]);
      }
      if (j < own_lo[1] || j > own_hi[1] || k < own_lo[2] || k > own_hi[2]) continue;
      for (int64_t i = own_lo[0]; i <= own_hi[0]; ++i) {
        const double val = row[i];
        st.sum += val;
        st.sum2 += val * val;
      }
      st.own += own_hi[0] - own_lo[0] + 1;
    }
  st.mn = double(mn);
  st.mx = double(mx);
  return st;
}

}  // namespace

MacrocellGrid build_macrocells(const Volume& v, int cell, FilterSupport support) {
  const auto t0 = std::chrono::steady_clock::now();
  MacrocellGrid g;
  g.cell = cell > 0 ? cell : default_cell_size(v.dims());
  g.support = support;
  const Dims n = v.dims();
  for (int a = 0; a < 3; ++a) g.grid[a] = cells_along(n[a], g.cell);
  const size_t count = size_t(g.grid[0] * g.grid[1] * g.grid[2]);
  g.min.assign(count, 0.f);
  g.max.assign(count, 0.f);
  g.stddev.assign(count, 0.f);
  const int before = support == FilterSupport::Tricubic ? 1 : 0;
  const int after = support == FilterSupport::Tricubic ? 2 : 1;
  parallel_for(size_t(g.grid[1] * g.grid[2]), [&](size_t row) {
    const int64_t b = int64_t(row) % g.grid[1], c = int64_t(row) / g.grid[1];
    for (int64_t a = 0; a < g.grid[0]; ++a) {
      const int64_t cellidx[3] = {a, b, c};
      int64_t lo[3], hi[3], own_lo[3], own_hi[3];
      for (int x = 0; x < 3; ++x) {
        lo[x] = std::max<int64_t>(0, cellidx[x] * g.cell - before);
        hi[x] = std::min<int64_t>(n[x] - 1, (cellidx[x] + 1) * g.cell + after);
        own_lo[x] = cellidx[x] * g.cell;
        own_hi[x] = std::min<int64_t>(n[x] - 1, (cellidx[x] + 1) * g.cell - 1);
      }
      CellStats st;
      switch (v.type()) {
        case VoxelType::U8: st = cell_stats(v.data(), n, lo, hi, own_lo, own_hi); break;
        case VoxelType::U16:
          st = cell_stats(reinterpret_cast<const uint16_t*>(v.data()), n, lo, hi, own_lo, own_hi);
          break;
        case VoxelType::F32:
          st = cell_stats(reinterpret_cast<const float*>(v.data()), n, lo, hi, own_lo, own_hi);
          break;
      }
      const size_t idx = g.index(a, b, c);
      g.min[idx] = float(st.mn + v.value_offset);
      g.max[idx] = float(st.mx + v.value_offset);
      if (st.own > 0) {
        const double mean = st.sum / double(st.own);
        g.stddev[idx] = float(std::sqrt(std::max(0.0, st.sum2 / double(st.own) - mean * mean)));
      }
    }
  });
  g.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return g;
}

// Two passes, one per grid. A single pass over the tricubic windows serving both grids was
// tried (issue 13) and was no faster on the em volume (500-560 ms against 222 + 284 ms): the
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
    throw std::invalid_argument("macrocells " + g.to_string() + " do not fit the " + std::to_string(dims[0]) +
                                "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]) +
                                " volume (want " + want.to_string() + ")");
}

std::string MacrocellGrid::to_string() const {
  std::ostringstream s;
  s << "Macrocells{" << grid[0] << "x" << grid[1] << "x" << grid[2] << " cells of " << cell
    << " voxels, " << (support == FilterSupport::Tricubic ? "tricubic" : "trilinear") << " support}";
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
