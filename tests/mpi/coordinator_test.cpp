// Label mpi: rank 0's volume loader under `mpirun peakcast serve`
// (distributed::Coordinator::load), on one rank (mpirun -np 1), so the test can call it directly: the
// statistics reduced from the bricks equal a whole read's, rank 0 keeps no voxels, and every
// refusal names its reason and leaves the command channel usable. Several ranks: mpi_serve.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <unistd.h>

#include "core/generators.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"
#include "distributed/coordinator.h"

namespace fs = std::filesystem;
using namespace peakcast;

namespace {

struct Files {
  fs::path dir = fs::temp_directory_path() / ("peakcast_coord_" + std::to_string(::getpid()));
  fs::path u16 = dir / "blobs.nrrd", nan = dir / "nan.nrrd";
  Files() {
    fs::create_directories(dir);
    GeneratorSpec g;
    g.dims = {21, 17, 13};
    g.type = SourceType::U16;
    write_volume(u16, generate_volume(g));
    VolumeHeader h;
    h.dims = {9, 8, 7};
    h.source = SourceType::F32;
    Volume v(h);
    auto* p = reinterpret_cast<float*>(v.data());
    for (int64_t i = 0; i < v.voxel_count(); ++i) p[i] = float(i % 11) - 3.f;
    p[5] = std::numeric_limits<float>::quiet_NaN();
    p[40] = std::numeric_limits<float>::infinity();
    v.finalize_statistics();
    write_volume(nan, v);
  }
  ~Files() { fs::remove_all(dir); }
};

void expect_same_statistics(const fs::path& path) {
  distributed::Coordinator c(1);
  const LoadedVolume got = c.load(path, {});
  const Volume want = load_volume(path);
  EXPECT_FALSE(got.volume->has_voxels()) << "rank 0 keeps no voxels";
  EXPECT_EQ(got.volume->dims(), want.dims());
  EXPECT_EQ(got.volume->source_type(), want.source_type());
  EXPECT_EQ(got.volume->min_value, want.min_value);
  EXPECT_EQ(got.volume->max_value, want.max_value);
  EXPECT_EQ(got.volume->histogram, want.histogram);
  EXPECT_EQ(got.volume->border_histogram, want.border_histogram);
  EXPECT_EQ(got.volume->nonfinite_replaced, want.nonfinite_replaced);
  EXPECT_EQ(got.resident_bytes, int64_t(want.byte_size())) << "one rank's brick is the whole volume";
  auto held = c.lock();
  auto brick = c.take_loaded(held, got.volume.get());
  ASSERT_TRUE(brick);
  ASSERT_EQ(brick->second.voxels->byte_size(), want.byte_size());
  EXPECT_EQ(0, std::memcmp(brick->second.voxels->data(), want.data(), want.byte_size())) << "the brick's voxels";
  EXPECT_FALSE(c.take_loaded(held, got.volume.get())) << "taken once";
}

TEST(Coordinator, StatisticsFromTheBricksEqualAWholeRead) {
  Files f;
  expect_same_statistics(f.u16);
  expect_same_statistics(f.nan);
}

// Each refusal throws VolumeError naming why; a load after it still works (no rank is left in
// a collective the others skipped).
TEST(Coordinator, RefusalsNameTheirReasonAndTheChannelGoesOn) {
  Files f;
  distributed::Coordinator c(1);
  auto refused = [&](const fs::path& path, const LoadOptions& o, const std::string& why) {
    try {
      c.load(path, o);
      ADD_FAILURE() << path << " was not refused (" << why << ")";
    } catch (const VolumeError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_TRUE(c.load(f.u16, {}).volume) << "after refusing " << why;
  };
  LoadOptions small;
  small.max_voxels = 1000;
  refused(f.u16, small, "exceeds the limit of 1000");
  LoadOptions strict;
  strict.nonfinite = NonFinitePolicy::Refuse;
  refused(f.nan, strict, "2 NaN/Inf voxels (policy: refuse)");
  refused(f.dir / "missing.nrrd", {}, "missing.nrrd");
  // More ranks than the volume has cells: refused before any rank is asked (so a coordinator
  // of 64 ranks on this one-rank job never reaches a collective).
  GeneratorSpec g;
  g.dims = {3, 2, 2};
  write_volume(f.dir / "tiny.nrrd", generate_volume(g));
  try {
    distributed::Coordinator(64).load(f.dir / "tiny.nrrd", {});
    ADD_FAILURE() << "a volume of 2 cells was split among 64 ranks";
  } catch (const VolumeError& e) {
    EXPECT_NE(std::string(e.what()).find("tiny.nrrd"), std::string::npos) << e.what();
  }
  // Shutdown: after the last command, a load queued on the loader is refused.
  {
    auto held = c.lock();
    c.close(held);
  }
  try {
    c.load(f.u16, {});
    ADD_FAILURE() << "a load after close was not refused";
  } catch (const VolumeError& e) {
    EXPECT_NE(std::string(e.what()).find("shutting down"), std::string::npos) << e.what();
  }
}

}  // namespace

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  ::testing::InitGoogleTest(&argc, argv);
  const int rc = RUN_ALL_TESTS();
  MPI_Finalize();
  return rc;
}
