// Every real sample volume (tests/data, see PROVENANCE.md) loads with the right dims, type,
// spacing and value range. Expected ranges were read with Python's gzip/array modules.
#include <gtest/gtest.h>

#include "core/volume_io.h"
#include "unit/test_util.h"

using namespace peakcast;

namespace {

struct Expect {
  const char* file;
  Dims dims;
  SourceType type;
  glm::dvec3 spacing;
  double min, max;
};

void PrintTo(const Expect& e, std::ostream* os) { *os << e.file; }

class SampleData : public ::testing::TestWithParam<Expect> {};

TEST_P(SampleData, LoadsWithTheRightHeaderAndRange) {
  const Expect e = GetParam();
  Volume v = load_volume(test::data_dir() / e.file);
  EXPECT_EQ(v.dims(), e.dims);
  EXPECT_EQ(v.source_type(), e.type);
  EXPECT_EQ(v.spacing, e.spacing);
  EXPECT_EQ(v.min_value, e.min);
  EXPECT_EQ(v.max_value, e.max);
  EXPECT_GT(v.load_ms, 0.0);
}

INSTANTIATE_TEST_SUITE_P(
    All, SampleData,
    ::testing::Values(Expect{"heptane_151.nrrd", {151, 151, 151}, SourceType::U8, {1, 1, 1}, 0, 255},
                      Expect{"headsq/quarter.nhdr", {64, 64, 93}, SourceType::I16, {3.2, 3.2, 1.5}, 0, 3926},
                      Expect{"HeadMRVolume.mhd", {48, 62, 42}, SourceType::U8, {4, 4, 4}, 0, 255},
                      Expect{"nucleon.nhdr", {41, 41, 41}, SourceType::U8, {1, 1, 1}, 0, 249}),
    [](const auto& info) {
      std::string n = info.param.file;
      return n.substr(n.find('/') + 1, n.find('.') - n.find('/') - 1);
    });

TEST(SampleData, HeadsqVoxelValueMatchesTheSliceFile) {
  // quarter.41 holds z = 40; voxel (32, 32) read independently with Python: 540.
  Volume v = load_volume(test::data_dir() / "headsq/quarter.nhdr");
  EXPECT_EQ(v.value(32, 32, 40), 540.0);
}

}  // namespace
