#include "core/macrocell_share.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/parallel.h"

namespace peakcast {

namespace {

// One cell's share in one pass over rows of the voxel type (a type switch per voxel made the em
// volume's grids take over a second): the extremes over the filter's voxels [lo, hi] and the
// sums over the cell's own voxels [own_lo, own_hi] (inclusive, brick coordinates; the own box
// may be empty).
template <typename T>
void add_box(const T* data, const Dims& n, const int64_t lo[3], const int64_t hi[3], const int64_t own_lo[3],
             const int64_t own_hi[3], double offset, size_t idx, MacrocellShare& s) {
  T mn = data[size_t(lo[0] + n[0] * (lo[1] + n[1] * lo[2]))], mx = mn;
  double sum = 0, sum2 = 0, own = 0;
  for (int64_t k = lo[2]; k <= hi[2]; ++k)
    for (int64_t j = lo[1]; j <= hi[1]; ++j) {
      const T* row = data + size_t(n[0] * (j + n[1] * k));
      for (int64_t i = lo[0]; i <= hi[0]; ++i) {
        mn = std::min(mn, row[i]);
        mx = std::max(mx, row[i]);
      }
      if (j < own_lo[1] || j > own_hi[1] || k < own_lo[2] || k > own_hi[2] || own_lo[0] > own_hi[0]) continue;
      for (int64_t i = own_lo[0]; i <= own_hi[0]; ++i) {
        const double val = row[i];
        sum += val;
        sum2 += val * val;
      }
      own += double(own_hi[0] - own_lo[0] + 1);
    }
  // Added to what the share holds (a fresh share: +inf, -inf, zeros), as add_share adds.
  s.min[idx] = std::min(s.min[idx], float(double(mn) + offset));
  s.max[idx] = std::max(s.max[idx], float(double(mx) + offset));
  // The sums are of stored values, as the standard deviation needs no offset.
  s.sum[idx] += sum;
  s.sum2[idx] += sum2;
  s.own[idx] += own;
}

}  // namespace

MacrocellShare macrocell_share(const Volume& v, const Dims& whole, const Dims& count_lo, const Dims& count_hi,
                               FilterSupport support, int cell) {
  return macrocell_share_at(v, v.region_lo, whole, count_lo, count_hi, support, cell);
}

MacrocellShare macrocell_share_at(const Volume& v, const Dims& region_lo, const Dims& whole, const Dims& count_lo,
                                  const Dims& count_hi, FilterSupport support, int cell) {
  MacrocellShare s;
  add_macrocell_share_at(s, v, region_lo, whole, count_lo, count_hi, support, cell);
  return s;
}

void add_macrocell_share_at(MacrocellShare& s, const Volume& v, const Dims& region_lo, const Dims& whole,
                            const Dims& count_lo, const Dims& count_hi, FilterSupport support, int cell) {
  const Dims n = v.dims();
  for (int a = 0; a < 3; ++a)
    if (!(0 <= count_lo[a] && count_lo[a] < count_hi[a] && count_hi[a] <= n[a] && region_lo[a] >= 0 &&
          region_lo[a] + n[a] <= whole[a]))
      throw std::invalid_argument("macrocell_share: the counted box is not inside the brick and the volume");
  Dims grid{};
  const int edge = cell > 0 ? cell : default_cell_size(whole);
  for (int a = 0; a < 3; ++a) grid[a] = cells_along(whole[a], edge);
  const size_t count = size_t(grid[0] * grid[1] * grid[2]);
  if (s.min.empty()) {  // a fresh share
    s.cell = edge;
    s.support = support;
    s.grid = grid;
    s.min.assign(count, std::numeric_limits<float>::infinity());
    s.max.assign(count, -std::numeric_limits<float>::infinity());
    s.own.assign(count, 0.0);
    s.sum.assign(count, 0.0);
    s.sum2.assign(count, 0.0);
  } else if (s.cell != edge || s.grid != grid || s.support != support || s.min.size() != count) {
    throw std::invalid_argument("add_macrocell_share_at: the share is of another grid");
  }
  const int before = support == FilterSupport::Tricubic ? 1 : 0;
  const int after = support == FilterSupport::Tricubic ? 2 : 1;
  parallel_for(size_t(s.grid[1] * s.grid[2]), [&](size_t row) {
    const int64_t b = int64_t(row) % s.grid[1], c = int64_t(row) / s.grid[1];
    for (int64_t a = 0; a < s.grid[0]; ++a) {
      const int64_t at[3] = {a, b, c};
      int64_t lo[3], hi[3], own_lo[3], own_hi[3];
      bool empty = false;
      for (int x = 0; x < 3; ++x) {
        // build_macrocells's boxes in the whole volume, cut to the counted voxels, in brick coordinates.
        const int64_t first = region_lo[x] + count_lo[x], last = region_lo[x] + count_hi[x] - 1;
        lo[x] = std::max({int64_t(0), at[x] * s.cell - before, first}) - region_lo[x];
        hi[x] = std::min({whole[x] - 1, (at[x] + 1) * s.cell + after, last}) - region_lo[x];
        own_lo[x] = std::max(at[x] * s.cell, first) - region_lo[x];
        own_hi[x] = std::min({whole[x] - 1, (at[x] + 1) * s.cell - 1, last}) - region_lo[x];
        empty = empty || lo[x] > hi[x];
      }
      if (empty) continue;
      const size_t idx = size_t(a + s.grid[0] * (b + s.grid[1] * c));
      switch (v.type()) {
        case VoxelType::U8: add_box(v.data(), n, lo, hi, own_lo, own_hi, v.value_offset, idx, s); break;
        case VoxelType::U16:
          add_box(reinterpret_cast<const uint16_t*>(v.data()), n, lo, hi, own_lo, own_hi, v.value_offset, idx, s);
          break;
        case VoxelType::F32:
          add_box(reinterpret_cast<const float*>(v.data()), n, lo, hi, own_lo, own_hi, v.value_offset, idx, s);
          break;
      }
    }
  });
}

void add_share(MacrocellShare& into, const MacrocellShare& o) {
  if (o.cell != into.cell || o.grid != into.grid || o.support != into.support || o.min.size() != into.min.size())
    throw std::invalid_argument("add_share: the shares are of different grids");
  for (size_t i = 0; i < into.min.size(); ++i) {
    into.min[i] = std::min(into.min[i], o.min[i]);
    into.max[i] = std::max(into.max[i], o.max[i]);
    into.own[i] += o.own[i];
    into.sum[i] += o.sum[i];
    into.sum2[i] += o.sum2[i];
  }
}

MacrocellGrid grid_from_share(const MacrocellShare& s) {
  MacrocellGrid g;
  g.cell = s.cell;
  g.grid = s.grid;
  g.support = s.support;
  g.min = s.min;
  g.max = s.max;
  g.stddev.assign(s.min.size(), 0.f);
  for (size_t i = 0; i < s.min.size(); ++i) {
    if (!(s.min[i] <= s.max[i])) throw std::invalid_argument("grid_from_share: a cell got no voxels from any brick");
    if (s.own[i] > 0) {
      const double mean = s.sum[i] / s.own[i];
      g.stddev[i] = float(std::sqrt(std::max(0.0, s.sum2[i] / s.own[i] - mean * mean)));
    }
  }
  return g;
}

}  // namespace peakcast
