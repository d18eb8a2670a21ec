// The k-d split into one brick per rank, and the compositing order for a camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/macrocell_share.h"
#include "core/volume.h"
#include "distributed/kd_split.h"

using namespace peakcast::distributed;

namespace {

peakcast::Volume v_outside() {  // a box beyond the volume is refused
  peakcast::VolumeHeader h;
  h.dims = {4, 4, 4};
  peakcast::Volume v(h);
  v.box_histogram({0, 0, 0}, {5, 4, 4}, 0, 1);
  return v;
}

bool owns_cell(const Brick& b, const Index3& c) {
  for (int a = 0; a < 3; ++a)
    if (c[a] < b.lo[a] || c[a] + 1 > b.hi[a]) return false;
  return true;
}

TEST(KdSplit, BricksTileTheVolumeOnceForAnyRankCount) {
  const Index3 dims{17, 9, 12};
  for (int ranks = 1; ranks <= 9; ++ranks) {
    const KdSplit s = kd_split(dims, ranks, 2);
    ASSERT_EQ(int(s.bricks.size()), ranks);
    for (int64_t z = 0; z + 1 < dims[2]; ++z)
      for (int64_t y = 0; y + 1 < dims[1]; ++y)
        for (int64_t x = 0; x + 1 < dims[0]; ++x) {
          const int owners = int(std::count_if(s.bricks.begin(), s.bricks.end(), [&](const Brick& b) {
            return owns_cell(b, {x, y, z});
          }));
          ASSERT_EQ(owners, 1) << "cell " << x << "," << y << "," << z << " with " << ranks << " ranks";
        }
    for (int r = 0; r < ranks; ++r) EXPECT_EQ(s.bricks[r].rank, r);
  }
}

// A distributed volume's statistics are the sum of its bricks' (distributed/brick_load.cpp): every
// voxel, shared boundary planes and the volume's upper faces included, in one counted box.
TEST(KdSplit, CountedBoxesTileTheVoxelsOnceForAnyRankCount) {
  const Index3 dims{17, 9, 12};
  for (int ranks = 1; ranks <= 9; ++ranks) {
    const KdSplit s = kd_split(dims, ranks, 3);
    std::vector<int> counted(size_t(dims[0] * dims[1] * dims[2]), 0);
    for (const Brick& b : s.bricks) {
      const auto [lo, hi] = counted_box(b, dims);
      for (int a = 0; a < 3; ++a) {
        ASSERT_GE(lo[a], 0) << b.to_string();
        ASSERT_LE(hi[a], b.read_hi[a] - b.read_lo[a]) << "beyond the voxels read: " << b.to_string();
      }
      for (int64_t z = lo[2]; z < hi[2]; ++z)
        for (int64_t y = lo[1]; y < hi[1]; ++y)
          for (int64_t x = lo[0]; x < hi[0]; ++x)
            ++counted[size_t((x + b.read_lo[0]) + dims[0] * ((y + b.read_lo[1]) + dims[1] * (z + b.read_lo[2])))];
    }
    for (size_t i = 0; i < counted.size(); ++i)
      ASSERT_EQ(counted[i], 1) << "voxel " << i << " with " << ranks << " ranks";
  }
}

// The histogram a distributed server reports: its bricks' counted boxes, binned over the whole
// volume's range and summed, give finalize_statistics' bins exactly (float and uint16 voxels).
TEST(KdSplit, BrickHistogramsSumToTheWholeVolumesHistogram) {
  std::mt19937 rng(5);
  for (peakcast::SourceType t : {peakcast::SourceType::F32, peakcast::SourceType::I16}) {
    peakcast::VolumeHeader h;
    h.dims = {23, 14, 19};
    h.source = t;
    peakcast::Volume v(h);
    std::uniform_real_distribution<float> pick(-3.f, 7.f);
    for (size_t i = 0; i < size_t(v.voxel_count()); ++i) {
      if (t == peakcast::SourceType::F32)
        reinterpret_cast<float*>(v.data())[i] = pick(rng);
      else
        reinterpret_cast<uint16_t*>(v.data())[i] = uint16_t(30000 + 1000 * pick(rng));
    }
    v.finalize_statistics();
    EXPECT_EQ(v.box_histogram({0, 0, 0}, v.dims(), v.min_value - v.value_offset, v.max_value - v.value_offset),
              v.histogram);
    for (int ranks = 2; ranks <= 5; ++ranks) {
      const KdSplit s = kd_split(v.dims(), ranks, 3);
      std::vector<uint64_t> sum(v.histogram.size(), 0);
      for (const Brick& b : s.bricks) {
        auto [lo, hi] = counted_box(b, v.dims());
        for (int a = 0; a < 3; ++a) lo[a] += b.read_lo[a], hi[a] += b.read_lo[a];
        const auto part = v.box_histogram(lo, hi, v.min_value - v.value_offset, v.max_value - v.value_offset);
        for (size_t k = 0; k < sum.size(); ++k) sum[k] += part[k];
      }
      EXPECT_EQ(sum, v.histogram) << peakcast::to_string(t) << ", " << ranks << " ranks";
    }
  }
  peakcast::VolumeHeader h;
  h.dims = {4, 4, 4};
  const peakcast::Volume head = peakcast::Volume::header_only(h);
  EXPECT_FALSE(head.has_voxels());
  EXPECT_EQ(head.byte_size(), 64u);
  EXPECT_THROW(head.box_histogram({0, 0, 0}, head.dims(), 0, 1), std::logic_error);
  EXPECT_THROW(v_outside(), std::invalid_argument);
}

// A brick as a region read makes it: the voxels [read_lo, read_hi) of `v`, with region_lo and
// source_dims set.
peakcast::Volume crop(const peakcast::Volume& v, const Brick& b, peakcast::SourceType t) {
  peakcast::VolumeHeader h;
  h.source = t;
  for (int a = 0; a < 3; ++a) h.dims[a] = b.read_hi[a] - b.read_lo[a];
  peakcast::Volume c(h);
  const size_t bytes = peakcast::voxel_bytes(v.type()), row = size_t(h.dims[0]) * bytes;
  for (int64_t k = 0; k < h.dims[2]; ++k)
    for (int64_t j = 0; j < h.dims[1]; ++j) {
      const size_t from = size_t(b.read_lo[0] + v.dims()[0] * (b.read_lo[1] + j + v.dims()[1] * (b.read_lo[2] + k)));
      std::copy_n(v.data() + from * bytes, row, c.data() + size_t(h.dims[0] * (j + h.dims[1] * k)) * bytes);
    }
  c.value_offset = v.value_offset;
  c.source_dims = v.dims();
  c.region_lo = b.read_lo;
  return c;
}

// The whole volume's macrocell grids from the bricks' shares (core/macrocell_share.h) equal the
// grids built from the whole volume: min and max exactly, the standard deviation up to the
// order of its sums. Tried on a volume whose cells are 9 voxels (default_cell_size of 520).
TEST(KdSplit, BrickMacrocellSharesAddUpToTheWholeVolumesGrid) {
  std::mt19937 rng(11);
  for (auto [t, dims] : {std::pair{peakcast::SourceType::F32, Index3{23, 14, 19}},
                         std::pair{peakcast::SourceType::I16, Index3{31, 17, 12}},
                         std::pair{peakcast::SourceType::U8, Index3{520, 9, 11}}}) {
    peakcast::VolumeHeader h;
    h.dims = dims;
    h.source = t;
    peakcast::Volume v(h);
    std::uniform_real_distribution<float> pick(-3.f, 7.f);
    for (size_t i = 0; i < size_t(v.voxel_count()); ++i) {
      if (t == peakcast::SourceType::F32)
        reinterpret_cast<float*>(v.data())[i] = pick(rng);
      else if (t == peakcast::SourceType::U8)
        v.data()[i] = uint8_t(20 * pick(rng) + 60);
      else
        reinterpret_cast<uint16_t*>(v.data())[i] = uint16_t(30000 + 1000 * pick(rng));
    }
    v.finalize_statistics();
    for (peakcast::FilterSupport support : {peakcast::FilterSupport::Trilinear, peakcast::FilterSupport::Tricubic}) {
      const peakcast::MacrocellGrid want = peakcast::build_macrocells(v, 0, support);
      for (int ranks = 1; ranks <= 5; ++ranks) {
        const KdSplit s = kd_split(dims, ranks, 3);
        // direct: each brick added in place; both: both supports in one pass (an out-of-core still's)
        peakcast::MacrocellShare sum, direct, both[2];
        for (const Brick& b : s.bricks) {
          const peakcast::Volume brick = crop(v, b, t);
          const auto [lo, hi] = counted_box(b, dims);
          const peakcast::MacrocellShare part = peakcast::macrocell_share(brick, dims, lo, hi, support);
          if (b.rank == 0)
            sum = part;
          else
            peakcast::add_share(sum, part);
          peakcast::add_macrocell_share_at(direct, brick, brick.region_lo, dims, lo, hi, support);
          peakcast::add_macrocell_shares_at(both[0], both[1], brick, brick.region_lo, dims, lo, hi);
        }
        const peakcast::MacrocellShare& one_pass = both[support == peakcast::FilterSupport::Tricubic ? 1 : 0];
        EXPECT_EQ(one_pass.support, support);
        EXPECT_EQ(one_pass.min, sum.min);
        EXPECT_EQ(one_pass.max, sum.max);
        EXPECT_EQ(one_pass.own, sum.own);
        EXPECT_EQ(one_pass.sum, sum.sum);
        EXPECT_EQ(one_pass.sum2, sum.sum2);
        EXPECT_EQ(direct.min, sum.min);
        EXPECT_EQ(direct.max, sum.max);
        EXPECT_EQ(direct.own, sum.own);
        EXPECT_EQ(direct.sum, sum.sum) << "bit for bit, as add_share adds";
        EXPECT_EQ(direct.sum2, sum.sum2);
        const peakcast::MacrocellGrid got = peakcast::grid_from_share(sum);
        ASSERT_EQ(got.cell, want.cell);
        ASSERT_EQ(got.grid, want.grid);
        EXPECT_EQ(got.min, want.min) << ranks << " ranks";
        EXPECT_EQ(got.max, want.max) << ranks << " ranks";
        for (size_t c = 0; c < want.size(); ++c)
          ASSERT_NEAR(got.stddev[c], want.stddev[c], 1e-5 * (1.0 + want.stddev[c])) << ranks << " ranks, cell " << c;
      }
    }
    // Refusals: a counted box outside the brick, shares of different grids, a cell no share covers.
    const KdSplit two = kd_split(dims, 2, 3);
    const peakcast::Volume brick = crop(v, two.bricks[0], t);
    auto [lo, hi] = counted_box(two.bricks[0], dims);
    Index3 past = hi;
    past[0] = brick.dims()[0] + 1;
    EXPECT_THROW(peakcast::macrocell_share(brick, dims, lo, past, peakcast::FilterSupport::Trilinear),
                 std::invalid_argument);
    const peakcast::MacrocellShare a =
        peakcast::macrocell_share(brick, dims, lo, hi, peakcast::FilterSupport::Trilinear);
    peakcast::MacrocellShare b = peakcast::macrocell_share(brick, dims, lo, hi, peakcast::FilterSupport::Tricubic);
    EXPECT_THROW(peakcast::add_share(b, a), std::invalid_argument);
    EXPECT_THROW(
        peakcast::add_macrocell_share_at(b, brick, brick.region_lo, dims, lo, hi, peakcast::FilterSupport::Trilinear),
        std::invalid_argument);
    EXPECT_THROW(peakcast::grid_from_share(a), std::invalid_argument);  // the other brick's cells are missing
  }
}

TEST(KdSplit, SharesFollowTheRankCountOnTheReferenceVolume) {
  const Index3 dims{900, 500, 930};
  const double cells = 899.0 * 499.0 * 929.0;
  for (int ranks : {2, 3, 4, 5, 7}) {
    const KdSplit s = kd_split(dims, ranks, 1);
    for (const Brick& b : s.bricks) {
      const double share = double(b.hi[0] - b.lo[0]) * double(b.hi[1] - b.lo[1]) * double(b.hi[2] - b.lo[2]) / cells;
      EXPECT_NEAR(share * ranks, 1.0, 0.01) << b.to_string();
    }
  }
}

TEST(KdSplit, GhostsAreTheFiltersSupportClampedToTheVolume) {
  EXPECT_EQ(ghost_voxels(false, false), 1);
  EXPECT_EQ(ghost_voxels(true, false), 2);
  EXPECT_EQ(ghost_voxels(true, true), 3);
  const KdSplit s = kd_split({40, 10, 10}, 2, 2);
  const Brick &a = s.bricks[0], &b = s.bricks[1];
  EXPECT_EQ(a.hi[0], b.lo[0]);  // the shared plane
  EXPECT_EQ(a.read_lo[0], 0);
  EXPECT_EQ(a.read_hi[0], a.hi[0] + 1 + 2);  // voxels up to hi + ghost, exclusive end
  EXPECT_EQ(b.read_lo[0], b.lo[0] - 2);
  EXPECT_EQ(b.read_hi[0], 40);
  EXPECT_EQ(a.read_lo[1], 0);
  EXPECT_EQ(a.read_hi[1], 10);
}

TEST(KdSplit, RefusesMoreRanksThanCells) {
  EXPECT_THROW(kd_split({3, 2, 2}, 5, 1), std::invalid_argument);
  EXPECT_THROW(kd_split({8, 8, 8}, 0, 1), std::invalid_argument);
  EXPECT_NO_THROW(kd_split({3, 2, 2}, 2, 1));
}

// Every ray from the eye enters the bricks in an order consistent with visibility_order.
TEST(KdSplit, VisibilityOrderIsTheOrderRaysMeetTheBricks) {
  const Index3 dims{30, 20, 25};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-40.0, 70.0), in(0.0, 1.0);
  for (int ranks : {2, 3, 5, 8}) {
    const KdSplit s = kd_split(dims, ranks, 1);
    for (int trial = 0; trial < 40; ++trial) {
      const bool ortho = trial % 2 == 1;
      const glm::dvec3 eye(u(rng), u(rng), u(rng));
      const glm::dvec3 dir = glm::normalize(glm::dvec3(in(rng)-0.5, in(rng)-0.5, in(rng)-0.5));
      const std::vector<int> order = visibility_order(s, eye, dir, ortho);
      ASSERT_EQ(int(order.size()), ranks);
      std::vector<int> position(static_cast<size_t>(ranks), 0);
      for (int i = 0; i < ranks; ++i) position[size_t(order[size_t(i)])] = i;
      for (int ray = 0; ray < 30; ++ray) {
        const glm::dvec3 target(in(rng)*29, in(rng)*19, in(rng)*24);
        const glm::dvec3 origin = ortho ? target - dir * 100.0 : eye;
        const glm::dvec3 d = ortho ? dir : glm::normalize(target - eye);
        int last = -1;
        for (double t = 0; t < 250; t += 0.05) {
          const glm::dvec3 p = origin + d * t;
          for (const Brick& b : s.bricks) {
            bool inside = true;
            for (int a = 0; a < 3; ++a) inside = inside && p[a] > b.lo[a] && p[a] < b.hi[a];
            if (inside) {
              ASSERT_GE(position[size_t(b.rank)], last) << "ray met rank " << b.rank << " after a later one";
              last = position[size_t(b.rank)];
            }
          }
        }
      }
    }
  }
}

}  // namespace
