#include "core/occupancy.h"
#include "core/value_range.h"

#include <algorithm>
#include <chrono>
#include <cmath>

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
  out.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace peakcast
