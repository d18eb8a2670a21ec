#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/macrocells.h"
#include "unit/test_util.h"

using namespace peakcast;

namespace {

Volume random_volume(Dims d, uint32_t seed) {
  VolumeHeader h;
  h.dims = d;
  h.source = SourceType::F32;
  Volume v(h);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  auto* p = reinterpret_cast<float*>(v.data());
  for (int64_t i = 0; i < v.voxel_count(); ++i) p[i] = u(rng);
  v.finalize_statistics();
  return v;
}

// Brute force: every sample position inside the cell, and every voxel its filter reads.
void check_against_brute_force(const Volume& v, const MacrocellGrid& g) {
  const Dims n = v.dims();
  const int before = g.support == FilterSupport::Tricubic ? 1 : 0, after = g.support == FilterSupport::Tricubic ? 2 : 1;
  for (int64_t c = 0; c < g.grid[2]; ++c)
    for (int64_t b = 0; b < g.grid[1]; ++b)
      for (int64_t a = 0; a < g.grid[0]; ++a) {
        double mn = 1e300, mx = -1e300, sum = 0, sum2 = 0;
        int64_t cnt = 0;
        const int64_t cell[3] = {a, b, c};
        int64_t lo[3], hi[3];
        for (int x = 0; x < 3; ++x) {
          // sample positions span [c*e, min((c+1)*e, n-1)]; floor(x) spans [c*e, that]
          const int64_t p0 = cell[x] * g.cell, p1 = std::min((cell[x] + 1) * g.cell, n[x] - 1);
          lo[x] = std::max<int64_t>(0, p0 - before);
          hi[x] = std::min<int64_t>(n[x] - 1, p1 + after);
        }
        for (int64_t k = lo[2]; k <= hi[2]; ++k)
          for (int64_t j = lo[1]; j <= hi[1]; ++j)
            for (int64_t i = lo[0]; i <= hi[0]; ++i) {
              mn = std::min(mn, v.value(i, j, k));
              mx = std::max(mx, v.value(i, j, k));
            }
        for (int64_t k = c * g.cell; k < std::min((c + 1) * g.cell, n[2]); ++k)
          for (int64_t j = b * g.cell; j < std::min((b + 1) * g.cell, n[1]); ++j)
            for (int64_t i = a * g.cell; i < std::min((a + 1) * g.cell, n[0]); ++i) {
              sum += v.value(i, j, k);
              sum2 += v.value(i, j, k) * v.value(i, j, k);
              ++cnt;
            }
        const size_t idx = g.index(a, b, c);
        ASSERT_EQ(g.min[idx], float(mn)) << a << "," << b << "," << c;
        ASSERT_EQ(g.max[idx], float(mx)) << a << "," << b << "," << c;
        const double mean = sum / double(cnt);
        ASSERT_NEAR(g.stddev[idx], std::sqrt(std::max(0.0, sum2 / double(cnt) - mean * mean)), 1e-4);
      }
}

TEST(Macrocells, MinMaxEqualBruteForceOnOddDims) {
  uint32_t seed = 1;
  for (Dims d : {Dims{17, 9, 23}, Dims{33, 31, 2}, Dims{1, 5, 40}, Dims{50, 41, 29}})
    for (int cell : {3, 4, 8})
      for (auto support : {FilterSupport::Trilinear, FilterSupport::Tricubic}) {
        Volume v = random_volume(d, seed++);
        MacrocellGrid g = build_macrocells(v, cell, support);
        for (int a = 0; a < 3; ++a) EXPECT_EQ(g.grid[a], cells_along(d[a], cell));
        check_against_brute_force(v, g);
      }
}

TEST(Macrocells, DefaultGridIsAtMost64PerAxis) {
  for (Dims d : {Dims{900, 500, 930}, Dims{41, 41, 41}, Dims{2048, 64, 3}}) {
    const int cell = default_cell_size(d);
    EXPECT_GE(cell, 8);
    for (int a = 0; a < 3; ++a) EXPECT_LE(cells_along(d[a], cell), 64);
  }
}

TEST(Macrocells, ValueOffsetApplied) {
  VolumeHeader h;
  h.dims = {4, 4, 4};
  h.source = SourceType::I16;
  Volume v(h);
  std::fill_n(reinterpret_cast<uint16_t*>(v.data()), 64, uint16_t(32768 - 100));  // -100 physical
  v.finalize_statistics();
  MacrocellGrid g = build_macrocells(v, 8);
  EXPECT_EQ(g.min[0], -100.f);
  EXPECT_EQ(g.max[0], -100.f);
}

}  // namespace
