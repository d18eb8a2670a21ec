#include "core/occupancy.h"
#include "core/value_range.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace peakcast {

Occupancy classify_cells(const MacrocellGrid& grid, const TransferFunction& tf, double lo, double hi,
                         const std::vector<double>& peak_values, int n, double overshoot) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<float> table = tf.bake(n, lo, hi);
  // Sparse table of maxima over power-of-two runs of opacity entries.
  std::vector<std::vector<float>> sparse(1, std::vector<float>(size_t(n)));
  for (int k = 0; k < n; ++k) sparse[0][size_t(k)] = table[size_t(k) * 4 + 3];
  for (int level = 1; (1 << level) <= n; ++level) {
    const auto& prev = sparse.back();
    std::vector<float> next(size_t(n - (1 << level) + 1));
    for (size_t k = 0; k < next.size(); ++k) next[k] = std::max(prev[k], prev[k + (size_t(1) << (level - 1))]);
    sparse.push_back(std::move(next));
  }
  auto range_max = [&](int a, int b) {  // inclusive
    const int level = 31 - __builtin_clz(unsigned(b - a + 1));
    return std::max(sparse[size_t(level)][size_t(a)], sparse[size_t(level)][size_t(b - (1 << level) + 1)]);
  };
  const double scale = double(n - 1) / table_range(lo, hi).width();
  Occupancy out;
  out.occupied.resize(grid.size());
  for (size_t c = 0; c < grid.size(); ++c) {
    const double widen = overshoot * (double(grid.max[c]) - double(grid.min[c]));
    const double cmin = grid.min[c] - widen, cmax = grid.max[c] + widen;
    const int a = std::clamp(int(std::floor((cmin - lo) * scale)) - 1, 0, n - 1);
    const int b = std::clamp(int(std::ceil((cmax - lo) * scale)) + 1, 0, n - 1);
    bool visible = range_max(a, b) > 0.f;
    for (double v : peak_values) visible = visible || (v >= cmin && v <= cmax);
    out.occupied[c] = visible ? 1 : 0;
    out.empty_cells += out.occupied[c] ? 0 : 1;
  }
  out.distance = empty_space_distance(grid.grid, out.occupied);
  out.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::vector<uint8_t> empty_space_distance(const Dims& grid, const std::vector<uint8_t>& occupied) {
  // d(x) = min over occupied y of max_a |x_a - y_a|, computed one axis at a time: after the pass
  // along axis a, g(x) = min over y with the same later coordinates of max(|x_0 - y_0|, ...,
  // |x_a - y_a|). A pass combines with max(|offset|, previous), exact for L-infinity.
  const int64_t nx = grid[0], ny = grid[1], nz = grid[2];
  const size_t count = size_t(nx * ny * nz);
  if (occupied.size() != count) throw std::invalid_argument("empty_space_distance: grid and cells differ");
  constexpr int kFar = 1 << 20;
  std::vector<int> d(count);
  for (size_t i = 0; i < count; ++i) d[i] = occupied[i] ? 0 : kFar;
  const int64_t stride[3] = {1, nx, nx * ny};
  const int64_t n[3] = {nx, ny, nz};
  std::vector<int> line, out;
  for (int axis = 0; axis < 3; ++axis) {
    const int64_t len = n[axis], st = stride[axis];
    line.resize(size_t(len));
    out.resize(size_t(len));
    for (size_t start = 0; start < count; ++start) {
      // Visit each line once, from its first cell (coordinate 0 on this axis).
      if ((int64_t(start) / st) % len != 0) continue;
      for (int64_t k = 0; k < len; ++k) line[size_t(k)] = d[start + size_t(k * st)];
      if (*std::min_element(line.begin(), line.end()) == kFar) continue;  // nothing near: stays far
      for (int64_t k = 0; k < len; ++k) {
        // Outward from k: a cell r away gives at least r, so the search ends once r >= best.
        int best = line[size_t(k)];
        for (int64_t r = 1; r < best && (k - r >= 0 || k + r < len); ++r) {
          if (k - r >= 0) best = std::min(best, std::max(int(r), line[size_t(k - r)]));
          if (k + r < len) best = std::min(best, std::max(int(r), line[size_t(k + r)]));
        }
        out[size_t(k)] = best;
      }
      for (int64_t k = 0; k < len; ++k) d[start + size_t(k * st)] = out[size_t(k)];
    }
  }
  std::vector<uint8_t> bytes(count);
  for (size_t i = 0; i < count; ++i) bytes[i] = uint8_t(std::min(d[i], kMaxEmptyDistance));
  return bytes;
}

}  // namespace peakcast
