// LoadOptions::progress: what the server tells a client while a volume is read. Every reader
// (raw read in one thread or in parallel, gzip, TIFF slices, a region) reports a rising fraction,
// one call at a time, ending with exactly one 1 after the statistics.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "core/generators.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;

namespace {

// Records the fractions, and whether two calls ever overlapped.
struct Recorder {
  std::vector<double> told;
  std::atomic<int> inside{0};
  bool overlapped = false;
  std::mutex m;

  LoadOptions options() {
    LoadOptions o;
    o.progress = [this](double f) {
      if (inside.fetch_add(1) != 0) overlapped = true;
      {
        std::lock_guard lock(m);
        told.push_back(f);
      }
      inside.fetch_sub(1);
    };
    return o;
  }

  // Rising, within (0, 1], the last exactly 1 and the only 1; at least `steps` reports before it.
  void expect_a_rising_count_to_one(size_t steps) const {
    ASSERT_FALSE(told.empty());
    EXPECT_FALSE(overlapped);
    EXPECT_EQ(told.back(), 1.0);
    EXPECT_GE(told.size(), steps + 1) << "too few reports before the end";
    for (size_t i = 0; i < told.size(); ++i) {
      EXPECT_GT(told[i], 0.0);
      if (i > 0) EXPECT_GT(told[i], told[i - 1]) << "report " << i;
      if (i + 1 < told.size()) EXPECT_LT(told[i], 1.0) << "a 1 before the end";
    }
  }
};

Volume ramp(const Dims& dims, SourceType type = SourceType::U16) {
  GeneratorSpec s;
  s.kind = GeneratorKind::Ramp;
  s.dims = dims;
  s.type = type;
  return generate_volume(s);
}

// Writes `v` to `file`, loads it back while `r` records the progress, and checks the voxels.
void write_and_load(const fs::path& file, const Volume& v, WriteOptions w, Recorder& r) {
  write_volume(file, v, w);
  EXPECT_TRUE(test::same_volume(v, load_volume(file, r.options())));
}

TEST(LoadProgress, RawReadInPiecesRisesToOne) {
  test::TempDir dir;
  Recorder r;
  write_and_load(dir / "v.nrrd", ramp({256, 256, 160}), {}, r);  // 20 MiB: 8 MiB pieces on one thread
  r.expect_a_rising_count_to_one(2);
}

TEST(LoadProgress, ParallelRawReadTellsOneAtATime) {
  test::TempDir dir;
  Recorder r;
  write_and_load(dir / "v.nhdr", ramp({256, 256, 512}), {}, r);  // 64 MiB: the workers, 8 MiB a pread
  r.expect_a_rising_count_to_one(7);
}

TEST(LoadProgress, GzipCountsInflatedBytes) {
  test::TempDir dir;
  Recorder r;
  write_and_load(dir / "v.nrrd", ramp({128, 128, 128}), {true}, r);  // 4 MiB inflated, 1 MiB at a time
  r.expect_a_rising_count_to_one(3);
}

TEST(LoadProgress, TiffSlicesEachCount) {
  using namespace OIIO;
  test::TempDir dir;
  const Volume v = ramp({16, 8, 10}, SourceType::U8);
  const fs::path slices = dir / "slices";
  fs::create_directories(slices);
  for (int z = 0; z < 10; ++z) {
    auto out = ImageOutput::create("tif");
    const fs::path p = slices / ("s_" + std::to_string(z) + ".tif");
    ASSERT_TRUE(out->open(p.string(), ImageSpec(16, 8, 1, TypeDesc::UINT8)));
    ASSERT_TRUE(out->write_image(TypeDesc::UINT8, v.data() + z * 16 * 8));
    out->close();
  }
  Recorder r;
  Volume back = load_volume(slices, r.options());
  EXPECT_TRUE(test::same_volume(v, back));
  r.expect_a_rising_count_to_one(9);  // a slice is 10%
}

TEST(LoadProgress, ARegionEndsWithOne) {
  test::TempDir dir;
  write_volume(dir / "v.nrrd", ramp({32, 32, 32}));
  Recorder r;
  LoadOptions o = r.options();
  o.region = VoxelRegion{{4, 4, 4}, {20, 20, 20}};
  load_volume(dir / "v.nrrd", o);
  r.expect_a_rising_count_to_one(0);
}

TEST(LoadProgress, AFailedReadNeverSaysOne) {
  test::TempDir dir;
  write_volume(dir / "v.nrrd", ramp({64, 64, 64}), {true});
  // Cut the gzip stream short: the read fails after some progress, and 1 is never told.
  const auto size = fs::file_size(dir / "v.nrrd");
  fs::resize_file(dir / "v.nrrd", size - size / 3);
  Recorder r;
  EXPECT_THROW(load_volume(dir / "v.nrrd", r.options()), VolumeError);
  for (double f : r.told) EXPECT_LT(f, 1.0);
}

}  // namespace
