// A rank reads only its brick. Every format that supports it gives the same voxels as
// cropping the whole volume, with the origin moved to the region's first voxel.
#include <gtest/gtest.h>

#include <cstring>

#include "core/generators.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;

namespace {

Volume sample(SourceType type) { return test::anisotropic_blobs(type, {23, 11, 9}); }

void expect_crop(const Volume& whole, const Volume& part, const VoxelRegion& r) {
  ASSERT_EQ(part.dims()[0], r.hi[0] - r.lo[0]);
  ASSERT_EQ(part.dims()[1], r.hi[1] - r.lo[1]);
  ASSERT_EQ(part.dims()[2], r.hi[2] - r.lo[2]);
  for (int a = 0; a < 3; ++a) EXPECT_DOUBLE_EQ(part.origin[a], whole.origin[a] + double(r.lo[a]) * whole.spacing[a]);
  EXPECT_EQ(part.spacing, whole.spacing);
  const size_t bpv = voxel_bytes(whole.type());
  const auto& d = whole.dims();
  int64_t mismatched = 0;
  for (int64_t z = r.lo[2]; z < r.hi[2]; ++z)
    for (int64_t y = r.lo[1]; y < r.hi[1]; ++y) {
      const uint8_t* src = whole.data() + size_t(((z * d[1] + y) * d[0] + r.lo[0])) * bpv;
      const uint8_t* dst =
          part.data() + size_t((((z - r.lo[2]) * part.dims()[1] + (y - r.lo[1])) * part.dims()[0])) * bpv;
      mismatched += std::memcmp(src, dst, size_t(r.hi[0] - r.lo[0]) * bpv) != 0;
    }
  EXPECT_EQ(mismatched, 0) << "rows differing from the crop of the whole volume";
}

struct Case {
  SourceType type;
  std::string ext;
  bool gzip;
};
void PrintTo(const Case& c, std::ostream* os) { *os << to_string(c.type) << c.ext << (c.gzip ? ".gz" : ""); }

class Region : public ::testing::TestWithParam<Case> {};

TEST_P(Region, EqualsTheCropOfTheWholeVolume) {
  const Case c = GetParam();
  test::TempDir dir;
  const Volume v = sample(c.type);
  const fs::path file = dir / ("v" + c.ext);
  write_volume(file, v, WriteOptions{c.gzip});
  const Volume whole = load_volume(file);
  for (VoxelRegion r :
       {VoxelRegion{{0, 0, 0}, {23, 11, 9}}, VoxelRegion{{3, 2, 1}, {17, 9, 8}}, VoxelRegion{{22, 10, 8}, {23, 11, 9}},
        VoxelRegion{{0, 5, 0}, {23, 6, 9}}, VoxelRegion{{5, 0, 4}, {6, 11, 5}}}) {
    LoadOptions o;
    o.region = r;
    expect_crop(whole, load_volume(file, o), r);
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, Region,
                         ::testing::Values(Case{SourceType::U8, ".raw", false}, Case{SourceType::U16, ".raw", true},
                                           Case{SourceType::I16, ".nrrd", false}, Case{SourceType::F32, ".nrrd", true},
                                           Case{SourceType::U16, ".nhdr", false}, Case{SourceType::U8, ".nhdr", true},
                                           Case{SourceType::I8, ".mhd", false}, Case{SourceType::F32, ".mha", false}));

// Compressed data larger than the 1 MiB inflate chunk: regions whose rows straddle a chunk
// boundary, and one that ends early (the reader stops inflating after its last row).
TEST(Region, CompressedRowsAcrossInflateChunks) {
  test::TempDir dir;
  const Volume v = test::anisotropic_blobs(SourceType::U16, {170, 97, 41});  // 1.35 MB of voxels
  write_volume(dir / "big.nrrd", v, WriteOptions{true});
  const Volume whole = load_volume(dir / "big.nrrd");
  // Rows of 340 bytes, slices of 32980: byte 1 MiB = 1048576 lies in the row y = 77 of slice
  // z = 31 (it starts at 1048560), which the first two regions read across the boundary.
  for (VoxelRegion r : {VoxelRegion{{1, 70, 31}, {169, 85, 32}}, VoxelRegion{{0, 0, 0}, {170, 97, 41}},
                        VoxelRegion{{100, 0, 0}, {101, 97, 41}}, VoxelRegion{{0, 0, 0}, {170, 97, 2}}}) {
    LoadOptions o;
    o.region = r;
    expect_crop(whole, load_volume(dir / "big.nrrd", o), r);
  }
}

TEST(Region, SpreadOverSeveralDataFiles) {
  // A detached NRRD whose slices are separate files (data file: LIST): rows come from each file.
  test::TempDir dir;
  const Volume v = sample(SourceType::U16);
  write_volume(dir / "whole.nhdr", v);
  const Volume whole = load_volume(dir / "whole.nhdr");
  const size_t slice = size_t(23 * 11) * 2;
  std::string header =
      "NRRD0004\ntype: uint16\ndimension: 3\nsizes: 23 11 9\nencoding: raw\nendian: little\n"
      "spacings: 0.5 1.25 2\nspace origin: (-3,4.5,0.25)\ndata file: LIST\n";
  for (int z = 0; z < 9; ++z) {
    const std::string name = "s" + std::to_string(z) + ".raw";
    test::write_file(dir / name, std::string(reinterpret_cast<const char*>(whole.data()) + z * slice, slice));
    header += name + "\n";
  }
  test::write_file(dir / "list.nhdr", header);
  LoadOptions o;
  o.region = VoxelRegion{{4, 3, 2}, {20, 10, 7}};
  expect_crop(whole, load_volume(dir / "list.nhdr", o), *o.region);
}

TEST(Region, Refusals) {
  test::TempDir dir;
  const Volume v = sample(SourceType::U8);
  write_volume(dir / "v.nrrd", v);
  auto refused = [&](const fs::path& file, VoxelRegion r, const std::string& why) {
    LoadOptions o;
    o.region = r;
    try {
      load_volume(file, o);
      ADD_FAILURE() << "loaded " << file;
    } catch (const VolumeError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  refused(dir / "v.nrrd", {{0, 0, 0}, {24, 11, 9}}, "not inside the volume's 23 voxels");
  refused(dir / "v.nrrd", {{-1, 0, 0}, {5, 11, 9}}, "not inside");
  refused(dir / "v.nrrd", {{5, 0, 0}, {5, 11, 9}}, "not inside");
  // TIFF slices have no regions (an empty folder reads as a stack too, and is refused first).
  fs::create_directories(dir / "slices");
  test::write_file(dir / "slices/s000.tif", "not read");
  refused(dir / "slices", {{0, 0, 0}, {2, 2, 2}}, "a region of a TIFF stack cannot be read");
  // A folder of slices with one header is that header's volume, regions included.
  LoadOptions corner;
  corner.region = VoxelRegion{{0, 0, 0}, {2, 2, 2}};
  EXPECT_EQ(load_volume(test::data_dir() / "headsq", corner).dims(), (Dims{2, 2, 2}));
  // Two headers in one folder: which one is meant is not guessed.
  fs::create_directories(dir / "two");
  write_volume(dir / "two/a.nhdr", v);
  write_volume(dir / "two/b.nhdr", v);
  refused(dir / "two", {{0, 0, 0}, {2, 2, 2}}, "a folder with 2 volume headers");
  // A truncated file is refused even when the region lies in the part that exists.
  write_volume(dir / "t.nhdr", v);
  fs::resize_file(dir / "t.raw", 100);
  refused(dir / "t.nhdr", {{0, 0, 0}, {2, 2, 1}}, "truncated");
  // The voxel limit applies to the region: a brick of a volume larger than the limit loads.
  LoadOptions small;
  small.max_voxels = 1000;
  small.region = VoxelRegion{{0, 0, 0}, {10, 10, 9}};
  EXPECT_NO_THROW(load_volume(dir / "v.nrrd", small));
  small.region = VoxelRegion{{0, 0, 0}, {23, 11, 9}};
  EXPECT_THROW(load_volume(dir / "v.nrrd", small), VolumeError);
}

}  // namespace
