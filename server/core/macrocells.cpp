#include "core/macrocells.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

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
      int64_t lo[3], hi[3], own_hi[3];
      for (int x = 0; x < 3; ++x) {
        lo[x] = std::max<int64_t>(0, cellidx[x] * g.cell - before);
        hi[x] = std::min<int64_t>(n[x] - 1, (cellidx[x] + 1) * g.cell + after);
        own_hi[x] = std::min<int64_t>(n[x] - 1, (cellidx[x] + 1) * g.cell - 1);
      }
      double mn = std::numeric_limits<double>::infinity(), mx = -mn, sum = 0, sum2 = 0;
      int64_t own = 0;
      for (int64_t k = lo[2]; k <= hi[2]; ++k)
        for (int64_t j = lo[1]; j <= hi[1]; ++j)
          for (int64_t i = lo[0]; i <= hi[0]; ++i) {
            const double val = v.stored(size_t(i + n[0] * (j + n[1] * k)));
            mn = std::min(mn, val);
            mx = std::max(mx, val);
            if (i >= a * g.cell && i <= own_hi[0] && j >= b * g.cell && j <= own_hi[1] &&
                k >= c * g.cell && k <= own_hi[2]) {
              sum += val;
              sum2 += val * val;
              ++own;
            }
          }
      const size_t idx = g.index(a, b, c);
      g.min[idx] = float(mn + v.value_offset);
      g.max[idx] = float(mx + v.value_offset);
      if (own > 0) {
        const double mean = sum / double(own);
        g.stddev[idx] = float(std::sqrt(std::max(0.0, sum2 / double(own) - mean * mean)));
      }
    }
  });
  g.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return g;
}

std::string MacrocellGrid::to_string() const {
  std::ostringstream s;
  s << "Macrocells{" << grid[0] << "x" << grid[1] << "x" << grid[2] << " cells of " << cell
    << " voxels, " << (support == FilterSupport::Tricubic ? "tricubic" : "trilinear") << " support}";
  return s.str();
}

}  // namespace peakcast
