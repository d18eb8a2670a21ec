#include "core/macrocell_share.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "core/parallel.h"

namespace peakcast {

namespace {

// The sums of 8- and 16-bit voxels in exact integers (what double sums give while they stay below
// 2^53, a voxel at a time; these vectorise), of float voxels in double.
template <typename T>
using SumOf = std::conditional_t<std::is_integral_v<T>, uint64_t, double>;

// One cell of up to two shares in one pass over rows of the voxel type (a type switch per voxel
// made the em volume's grids take over a second): the extremes over each filter's voxels, the
// outer box (inclusive, brick coordinates) holding the inner one, and the sums over the cell's
// own voxels [own_lo, own_hi] (which may be empty), the same for both. Added to what the shares
// hold (a fresh share: +inf, -inf, zeros), as add_share adds.
template <typename T>
void add_boxes(const T* data, const Dims& n, const int64_t outer_lo[3], const int64_t outer_hi[3],
               const int64_t* inner_lo, const int64_t* inner_hi, const int64_t own_lo[3], const int64_t own_hi[3],
               double offset, size_t idx, MacrocellShare& outer, MacrocellShare* inner) {
  using L = std::numeric_limits<T>;
  const T top = L::has_infinity ? L::infinity() : L::max(), bottom = L::has_infinity ? -L::infinity() : L::lowest();
  T mn[2] = {top, top}, mx[2] = {bottom, bottom};  // [0]: outer, [1]: inner
  SumOf<T> sum = 0, sum2 = 0;
  double own = 0;
  const bool own_x = own_lo[0] <= own_hi[0];
  for (int64_t k = outer_lo[2]; k <= outer_hi[2]; ++k)
    for (int64_t j = outer_lo[1]; j <= outer_hi[1]; ++j) {
      const T* row = data + size_t(n[0] * (j + n[1] * k));
      auto extremes = [&](int64_t from, int64_t to, T& lo, T& hi) {
        for (int64_t i = from; i <= to; ++i) {
          lo = std::min(lo, row[i]);
          hi = std::max(hi, row[i]);
        }
      };
      if (inner && inner_lo[1] <= j && j <= inner_hi[1] && inner_lo[2] <= k && k <= inner_hi[2]) {
        extremes(inner_lo[0], inner_hi[0], mn[1], mx[1]);
        mn[0] = std::min(mn[0], mn[1]);
        mx[0] = std::max(mx[0], mx[1]);
        extremes(outer_lo[0], inner_lo[0] - 1, mn[0], mx[0]);
        extremes(inner_hi[0] + 1, outer_hi[0], mn[0], mx[0]);
      } else {
        extremes(outer_lo[0], outer_hi[0], mn[0], mx[0]);
      }
      if (j < own_lo[1] || j > own_hi[1] || k < own_lo[2] || k > own_hi[2] || !own_x) continue;
      for (int64_t i = own_lo[0]; i <= own_hi[0]; ++i) {
        const SumOf<T> val = SumOf<T>(row[i]);
        sum += val;
        sum2 += val * val;
      }
      own += double(own_hi[0] - own_lo[0] + 1);
    }
  for (int s = 0; s < (inner ? 2 : 1); ++s) {
    MacrocellShare& into = s == 0 ? outer : *inner;
    into.min[idx] = std::min(into.min[idx], float(double(mn[s]) + offset));
    into.max[idx] = std::max(into.max[idx], float(double(mx[s]) + offset));
    // The sums are of stored values, as the standard deviation needs no offset.
    into.sum[idx] += double(sum);
    into.sum2[idx] += double(sum2);
    into.own[idx] += own;
  }
}

// `s` made ready for a share of `grid` and `support`: filled when empty, checked when not.
void prepare(MacrocellShare& s, int edge, const Dims& grid, FilterSupport support) {
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
}

// Adds the brick's voxels to `outer` (a support's share) and, when given, `inner` (the trilinear
// share beside a tricubic outer one: its boxes lie inside the tricubic ones), in one pass.
void add_shares(MacrocellShare& outer, MacrocellShare* inner, const Volume& v, const Dims& region_lo, const Dims& whole,
                const Dims& count_lo, const Dims& count_hi, FilterSupport support, int cell) {
  const Dims n = v.dims();
  for (int a = 0; a < 3; ++a)
    if (!(0 <= count_lo[a] && count_lo[a] < count_hi[a] && count_hi[a] <= n[a] && region_lo[a] >= 0 &&
          region_lo[a] + n[a] <= whole[a]))
      throw std::invalid_argument("macrocell_share: the counted box is not inside the brick and the volume");
  Dims grid{};
  const int edge = cell > 0 ? cell : default_cell_size(whole);
  for (int a = 0; a < 3; ++a) grid[a] = cells_along(whole[a], edge);
  prepare(outer, edge, grid, support);
  if (inner) prepare(*inner, edge, grid, FilterSupport::Trilinear);
  // The footprint of a cell's filter: `before` voxels before it, `after` after its first voxel's
  // next cell (tricubic 1, 2; trilinear 0, 1).
  const int before = support == FilterSupport::Tricubic ? 1 : 0;
  const int after = support == FilterSupport::Tricubic ? 2 : 1;
  parallel_for(size_t(grid[1] * grid[2]), [&](size_t row) {
    const int64_t b = int64_t(row) % grid[1], c = int64_t(row) / grid[1];
    for (int64_t a = 0; a < grid[0]; ++a) {
      const int64_t at[3] = {a, b, c};
      int64_t lo[3], hi[3], in_lo[3], in_hi[3], own_lo[3], own_hi[3];
      bool empty = false, inner_empty = false;
      for (int x = 0; x < 3; ++x) {
        // build_macrocells's boxes in the whole volume, cut to the counted voxels, in brick coordinates.
        const int64_t first = region_lo[x] + count_lo[x], last = region_lo[x] + count_hi[x] - 1;
        lo[x] = std::max({int64_t(0), at[x] * edge - before, first}) - region_lo[x];
        hi[x] = std::min({whole[x] - 1, (at[x] + 1) * edge + after, last}) - region_lo[x];
        in_lo[x] = std::max(at[x] * edge, first) - region_lo[x];
        in_hi[x] = std::min({whole[x] - 1, (at[x] + 1) * edge + 1, last}) - region_lo[x];
        own_lo[x] = std::max(at[x] * edge, first) - region_lo[x];
        own_hi[x] = std::min({whole[x] - 1, (at[x] + 1) * edge - 1, last}) - region_lo[x];
        empty = empty || lo[x] > hi[x];
        inner_empty = inner_empty || in_lo[x] > in_hi[x];
      }
      if (empty) continue;  // the inner box is inside the outer one: empty too
      const size_t idx = size_t(a + grid[0] * (b + grid[1] * c));
      MacrocellShare* in = inner && !inner_empty ? inner : nullptr;
      switch (v.type()) {
        case VoxelType::U8:
          add_boxes(v.data(), n, lo, hi, in_lo, in_hi, own_lo, own_hi, v.value_offset, idx, outer, in);
          break;
        case VoxelType::U16:
          add_boxes(reinterpret_cast<const uint16_t*>(v.data()), n, lo, hi, in_lo, in_hi, own_lo, own_hi,
                    v.value_offset, idx, outer, in);
          break;
        case VoxelType::F32:
          add_boxes(reinterpret_cast<const float*>(v.data()), n, lo, hi, in_lo, in_hi, own_lo, own_hi, v.value_offset,
                    idx, outer, in);
          break;
      }
    }
  });
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
  add_shares(s, nullptr, v, region_lo, whole, count_lo, count_hi, support, cell);
}

void add_macrocell_shares_at(MacrocellShare& trilinear, MacrocellShare& tricubic, const Volume& v,
                             const Dims& region_lo, const Dims& whole, const Dims& count_lo, const Dims& count_hi,
                             int cell) {
  add_shares(tricubic, &trilinear, v, region_lo, whole, count_lo, count_hi, FilterSupport::Tricubic, cell);
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
