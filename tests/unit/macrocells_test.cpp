#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/macrocells.h"
#include "core/occupancy.h"
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
        const double sd = std::sqrt(std::max(0.0, sum2 / double(cnt) - mean * mean));
        ASSERT_NEAR(g.stddev[idx], sd, std::max(1e-4, 1e-6 * sd));  // stored as float: relative for 16-bit
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

// The builder reads each voxel type directly; every type must give the brute-force answer.
TEST(Macrocells, MinMaxEqualBruteForceForEveryVoxelType) {
  std::mt19937 rng(7);
  for (SourceType t : {SourceType::U8, SourceType::I8, SourceType::U16, SourceType::I16}) {
    VolumeHeader h;
    h.dims = {19, 12, 10};
    h.source = t;
    Volume v(h);
    std::uniform_int_distribution<int> u(0, t == SourceType::U8 || t == SourceType::I8 ? 255 : 65535);
    for (int64_t i = 0; i < v.voxel_count(); ++i) {
      if (v.type() == VoxelType::U8)
        v.data()[i] = uint8_t(u(rng));
      else
        reinterpret_cast<uint16_t*>(v.data())[i] = uint16_t(u(rng));
    }
    v.finalize_statistics();
    for (auto support : {FilterSupport::Trilinear, FilterSupport::Tricubic}) {
      SCOPED_TRACE(to_string(t));
      check_against_brute_force(v, build_macrocells(v, 4, support));
    }
  }
}

TEST(Macrocells, VolumeGridsAreBothSupportsAndChecked) {
  Volume v = random_volume({30, 20, 12}, 3), other = random_volume({30, 20, 30}, 4);
  const VolumeMacrocells m = build_volume_macrocells(v);
  ASSERT_TRUE(m.trilinear && m.tricubic);
  EXPECT_EQ(m.trilinear->support, FilterSupport::Trilinear);
  EXPECT_EQ(m.tricubic->support, FilterSupport::Tricubic);
  check_against_brute_force(v, *m.trilinear);
  check_against_brute_force(v, *m.tricubic);
  EXPECT_NO_THROW(check_macrocells(*m.trilinear, v, FilterSupport::Trilinear));
  // A grid of another volume, or of the other support, is refused by name.
  try {
    check_macrocells(*m.trilinear, other, FilterSupport::Trilinear);
    ADD_FAILURE() << "a grid of another volume was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("do not fit the 30x20x30 volume"), std::string::npos) << e.what();
  }
  EXPECT_THROW(check_macrocells(*m.trilinear, v, FilterSupport::Tricubic), std::invalid_argument);
  EXPECT_THROW(check_macrocells(build_macrocells(v, 3), v, FilterSupport::Trilinear), std::invalid_argument);
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

namespace {

// Lee eq. 8: with virtual samples a cell's [m, M] is widened by (M - m)/8 before classification,
// so a cell whose Catmull-Rom samples can overshoot into the TF's visible range is kept.
TEST(Occupancy, CatmullRomOvershootWidensTheCellsRange) {
  MacrocellGrid g;
  g.grid = {2, 1, 1};
  g.min = {0.0f, 0.9f};
  g.max = {0.8f, 1.0f};
  g.stddev = {0.1f, 0.01f};
  TransferFunction tf;
  tf.points = {{0.0, 0, 0, 0, 0}, {0.85, 1, 1, 1, 0}, {0.86, 1, 1, 1, 1}, {1.0, 1, 1, 1, 1}};
  const Occupancy plain = classify_cells(g, tf, 0.0, 1.0);
  EXPECT_EQ(plain.occupied, (std::vector<uint8_t>{0, 1}));
  // [0, 0.8] widened by 0.1 reaches 0.9, past the TF's first visible value.
  const Occupancy widened = classify_cells(g, tf, 0.0, 1.0, {}, TransferFunction::kTableSize, kCatmullRomOvershoot);
  EXPECT_EQ(widened.occupied, (std::vector<uint8_t>{1, 1}));
  EXPECT_EQ(widened.empty_cells, 0);
  // Peaks likewise: 0.88 lies outside [0, 0.8] but inside the widened range.
  TransferFunction dark;
  dark.points = {{0.0, 0, 0, 0, 0}, {1.0, 0, 0, 0, 0}};
  EXPECT_EQ(classify_cells(g, dark, 0.0, 1.0, {0.88}).occupied[0], 0);
  EXPECT_EQ(classify_cells(g, dark, 0.0, 1.0, {0.88}, TransferFunction::kTableSize, kCatmullRomOvershoot).occupied[0],
            1);
}

// A virtual sample's window reaches neighbouring cells: dilate_ranges joins each cell's range
// with those within `ring` cells (a cube), and nothing farther.
TEST(Macrocells, DilateRangesJoinsTheNeighbourhood) {
  MacrocellGrid g;
  g.grid = {5, 4, 3};
  const size_t n = size_t(5 * 4 * 3);
  g.min.assign(n, 0.2f);
  g.max.assign(n, 0.3f);
  g.stddev.assign(n, 0.0f);
  g.min[g.index(1, 1, 1)] = -1.0f;
  g.max[g.index(3, 2, 1)] = 5.0f;
  const MacrocellGrid same = dilate_ranges(g, 0);
  EXPECT_EQ(same.min, g.min);
  EXPECT_EQ(same.max, g.max);
  const MacrocellGrid d = dilate_ranges(g, 1);
  for (int64_t c = 0; c < 3; ++c)
    for (int64_t b = 0; b < 4; ++b)
      for (int64_t a = 0; a < 5; ++a) {
        const bool near_lo = std::abs(a - 1) <= 1 && std::abs(b - 1) <= 1 && std::abs(c - 1) <= 1;
        const bool near_hi = std::abs(a - 3) <= 1 && std::abs(b - 2) <= 1 && std::abs(c - 1) <= 1;
        EXPECT_EQ(d.min[g.index(a, b, c)], near_lo ? -1.0f : 0.2f) << a << b << c;
        EXPECT_EQ(d.max[g.index(a, b, c)], near_hi ? 5.0f : 0.3f) << a << b << c;
      }
  const MacrocellGrid d2 = dilate_ranges(g, 2);
  EXPECT_EQ(d2.max[g.index(0, 0, 0)], 0.3f);  // (3,2,1) is 3 cells away on x
  EXPECT_EQ(d2.max[g.index(1, 0, 0)], 5.0f);
}

}  // namespace

namespace peakcast {
namespace {

// The empty-space distance (what the GL traversal leaps by) against its definition: the
// Chebyshev distance in cells to the nearest occupied cell, on random grids of several shapes
// and densities, capped at kMaxEmptyDistance; a grid with nothing occupied is far everywhere.
TEST(Occupancy, EmptySpaceDistanceIsTheChebyshevDistanceToTheNearestOccupiedCell) {
  std::mt19937 rng(7);
  for (const Dims& n : {Dims{1, 1, 1}, Dims{7, 5, 3}, Dims{16, 9, 12}, Dims{33, 2, 17}})
    for (double density : {0.0, 0.002, 0.03, 0.5}) {
      std::vector<uint8_t> occ(size_t(n[0] * n[1] * n[2]));
      std::bernoulli_distribution pick(density);
      for (auto& o : occ) o = pick(rng) ? 1 : 0;
      const std::vector<uint8_t> d = empty_space_distance(n, occ);
      ASSERT_EQ(d.size(), occ.size());
      for (int64_t z = 0; z < n[2]; ++z)
        for (int64_t y = 0; y < n[1]; ++y)
          for (int64_t x = 0; x < n[0]; ++x) {
            int64_t want = kMaxEmptyDistance;
            for (int64_t c = 0; c < n[2]; ++c)
              for (int64_t b = 0; b < n[1]; ++b)
                for (int64_t a = 0; a < n[0]; ++a)
                  if (occ[size_t(a + n[0] * (b + n[1] * c))])
                    want = std::min(want, std::max({std::abs(a - x), std::abs(b - y), std::abs(c - z)}));
            ASSERT_EQ(d[size_t(x + n[0] * (y + n[1] * z))], want)
                << x << " " << y << " " << z << " density " << density;
          }
    }
  EXPECT_THROW(empty_space_distance({2, 2, 2}, std::vector<uint8_t>(7)), std::invalid_argument);
}

}  // namespace
}  // namespace peakcast
