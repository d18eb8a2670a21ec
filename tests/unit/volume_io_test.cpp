// Every loader and voxel type round-trips against a generated volume.
#include <gtest/gtest.h>
#include <algorithm>
#include <fstream>
#include <iterator>
#include <random>

#include <OpenImageIO/imageio.h>

#include "core/generators.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;

namespace {

Volume sample(SourceType type) { return test::anisotropic_blobs(type, {13, 7, 5}); }

struct Case {
  SourceType type;
  std::string ext;
  bool gzip;
};

void PrintTo(const Case& c, std::ostream* os) { *os << to_string(c.type) << c.ext; }

class RoundTrip : public ::testing::TestWithParam<Case> {};

TEST_P(RoundTrip, WriteThenLoadGivesTheSameVoxels) {
  test::TempDir dir;
  const Case c = GetParam();
  Volume v = sample(c.type);
  fs::path file = dir / ("v" + c.ext);
  write_volume(file, v, {c.gzip});
  Volume back = load_volume(file);
  EXPECT_TRUE(test::same_volume(v, back));
  EXPECT_EQ(back.min_value, v.min_value);
  EXPECT_EQ(back.max_value, v.max_value);
  EXPECT_EQ(back.histogram, v.histogram);
}

std::vector<Case> all_cases() {
  std::vector<Case> out;
  for (auto t : {SourceType::U8, SourceType::I8, SourceType::U16, SourceType::I16, SourceType::F32})
    for (std::string ext : {".raw", ".nrrd", ".nhdr", ".mhd", ".mha"})
      for (bool gz : {false, true})
        if (!(gz && (ext == ".mhd" || ext == ".mha"))) out.push_back({t, ext, gz});
  return out;
}

INSTANTIATE_TEST_SUITE_P(AllFormats, RoundTrip, ::testing::ValuesIn(all_cases()), [](const auto& info) {
  std::string n =
      std::string(to_string(info.param.type)) + "_" + info.param.ext.substr(1) + (info.param.gzip ? "_gz" : "");
  return n;
});

TEST(VolumeIo, SignedTypesKeepTheirPhysicalValues) {
  Volume v = sample(SourceType::I16);
  EXPECT_EQ(v.type(), VoxelType::U16);
  EXPECT_EQ(v.value_offset, -32768.0);
  EXPECT_LT(v.min_value, 0.0);  // blobs quantised to int16 start at -32768
}

TEST(VolumeIo, RawSidecarFoundFromEitherFile) {
  test::TempDir dir;
  Volume v = sample(SourceType::U16);
  write_volume(dir / "a.raw", v);
  EXPECT_TRUE(test::same_volume(v, load_volume(dir / "a.raw")));
  EXPECT_TRUE(test::same_volume(v, load_volume(dir / "a.raw.json")));
}

TEST(VolumeIo, BigEndianRawIsSwapped) {
  test::TempDir dir;
  const uint16_t values[] = {1, 256, 258, 65535, 0, 7, 9, 1000};
  std::string bytes;
  for (uint16_t x : values) bytes += {char(x >> 8), char(x & 0xff)};
  test::write_file(dir / "b.raw", bytes);
  test::write_file(dir / "b.raw.json", R"({"dims":[2,2,2],"dtype":"uint16","endian":"big"})");
  Volume v = load_volume(dir / "b.raw");
  for (int i = 0; i < 8; ++i) EXPECT_EQ(v.stored(size_t(i)), values[i]);
}

// Multi-page TIFF and a directory of numbered slices (natural order: 2 before 10).
// A damaged TIFF directory whose RowsPerStrip (1229520900) made OIIO allocate 4.9 GB for a 4x4
// LZW-or-unknown-compressed image (fuzz_tiff found it): refused before any read, naming the
// tag; a legal RowsPerStrip above the height (100 for 4 rows) still loads.
TEST(VolumeIo, TiffWithAHugeRowsPerStripIsRefused) {
  const fs::path seed = fs::path(PEAKCAST_SOURCE_DIR) / "tests/fuzz/seeds/fuzz_tiff/huge_rows_per_strip.tif";
  std::ifstream in(seed, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_FALSE(bytes.empty()) << seed;
  test::TempDir dir;
  const size_t comp = bytes.find(std::string("\x03\x01\x03\x00\x01\x00\x00\x00\x8e", 9));
  const size_t rps = bytes.find(std::string("\x16\x01\x04\x00\x01\x00\x00\x00", 8));
  ASSERT_NE(comp, std::string::npos);
  ASSERT_NE(rps, std::string::npos);
  for (char compression : {char(0x8e), char(5), char(8)}) {
    bytes[comp + 8] = compression;
    test::write_file(dir / "damaged.tif", bytes);
    try {
      load_volume(dir / "damaged.tif");
      ADD_FAILURE() << "loaded a TIFF claiming 1229520900 rows per strip, compression " << int(uint8_t(compression));
    } catch (const VolumeError& e) {
      EXPECT_NE(std::string(e.what()).find("RowsPerStrip 1229520900"), std::string::npos) << e.what();
    }
  }
  std::string legal = bytes;
  legal[comp + 8] = char(1);  // uncompressed, RowsPerStrip 100 > 4 rows
  legal.replace(rps + 8, 4, std::string("\x64\x00\x00\x00", 4));
  test::write_file(dir / "legal.tif", legal);
  EXPECT_EQ(load_volume(dir / "legal.tif").dims(), (Dims{4, 4, 1}));
}

TEST(VolumeIo, TiffStacks) {
  using namespace OIIO;
  test::TempDir dir;
  for (auto type : {SourceType::U8, SourceType::U16, SourceType::I16, SourceType::F32}) {
    GeneratorSpec s;
    s.kind = GeneratorKind::Ramp;
    s.dims = {9, 6, 12};
    s.type = type;
    Volume v = generate_volume(s);
    const TypeDesc td = type == SourceType::U8    ? TypeDesc::UINT8
                        : type == SourceType::U16 ? TypeDesc::UINT16
                        : type == SourceType::I16 ? TypeDesc::INT16
                                                  : TypeDesc::FLOAT;
    const size_t slice = size_t(9 * 6) * voxel_bytes(v.type());
    // Signed voxels were shifted on generation; shift back to int16 for the file.
    std::vector<uint8_t> file_bytes(v.data(), v.data() + v.byte_size());
    if (type == SourceType::I16) {
      for (size_t i = 1; i < file_bytes.size(); i += 2) file_bytes[i] ^= 0x80;
    }
    fs::path multipage = dir / ("stack_" + std::string(to_string(type)) + ".tif");
    {
      auto out = ImageOutput::create(multipage.string());
      ASSERT_TRUE(out->supports("multiimage"));
      std::vector<ImageSpec> specs(12, ImageSpec(9, 6, 1, td));
      ASSERT_TRUE(out->open(multipage.string(), 12, specs.data()));
      for (int z = 0; z < 12; ++z) {
        if (z > 0) {
          ASSERT_TRUE(out->open(multipage.string(), specs[z], ImageOutput::AppendSubimage));
        }
        ASSERT_TRUE(out->write_image(td, file_bytes.data() + z * slice));
      }
      out->close();
    }
    Volume a = load_volume(multipage);
    EXPECT_TRUE(test::same_volume(v, a)) << to_string(type);
    fs::path slices = dir / ("slices_" + std::string(to_string(type)));
    fs::create_directories(slices);
    for (int z = 0; z < 12; ++z) {
      auto out = ImageOutput::create("tif");
      fs::path p = slices / ("img_" + std::to_string(z + 1) + ".tif");
      ASSERT_TRUE(out->open(p.string(), ImageSpec(9, 6, 1, td)));
      ASSERT_TRUE(out->write_image(td, file_bytes.data() + z * slice));
      out->close();
    }
    Volume b = load_volume(slices);
    EXPECT_TRUE(test::same_volume(v, b)) << to_string(type);
  }
}

TEST(VolumeIo, FloatNonFiniteReplacedAndCounted) {
  test::TempDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float values[] = {1.0f, nan, 3.0f, inf, -inf, 2.0f, 0.5f, 2.5f};
  test::write_file(dir / "f.raw", std::string(reinterpret_cast<const char*>(values), sizeof values));
  test::write_file(dir / "f.raw.json", R"({"dims":[2,2,2],"dtype":"float32"})");
  Volume v = load_volume(dir / "f.raw");
  EXPECT_EQ(v.nonfinite_replaced, 3);
  EXPECT_EQ(v.min_value, 0.5);
  EXPECT_EQ(v.max_value, 3.0);
  EXPECT_EQ(v.stored(1), 0.5);  // NaN -> finite minimum
  EXPECT_EQ(v.stored(3), 3.0);  // +Inf -> finite maximum
  EXPECT_EQ(v.stored(4), 0.5);  // -Inf -> finite minimum
}

TEST(VolumeIo, HistogramCountsEveryVoxel) {
  Volume v = sample(SourceType::F32);
  uint64_t total = 0;
  for (auto c : v.histogram) total += c;
  EXPECT_EQ(total, uint64_t(v.voxel_count()));
  EXPECT_EQ(v.histogram.size(), size_t(Volume::kHistogramBins));
}

// Integer volumes get range and histogram from one counting pass: the same range
// and bins as the definition (bin = int((v - min) * bins / (max - min)), clamped), on random
// uint8 and uint16 voxels with value offsets (int8, int16), a constant volume and one voxel.
TEST(VolumeIo, IntegerStatisticsMatchTheirDefinition) {
  std::mt19937 rng(3);
  for (SourceType t : {SourceType::U8, SourceType::I8, SourceType::U16, SourceType::I16})
    for (Dims d : {Dims{1, 1, 1}, Dims{17, 9, 5}, Dims{64, 33, 20}})
      for (bool constant : {false, true}) {
        VolumeHeader h;
        h.dims = d;
        h.source = t;
        Volume v(h);
        v.value_offset = storage_offset(t);
        const bool wide = v.type() == VoxelType::U16;
        std::uniform_int_distribution<int> pick(wide ? 1000 : 10, wide ? 60000 : 200);
        const int fixed = pick(rng);
        for (size_t i = 0; i < size_t(v.voxel_count()); ++i) {
          const int x = constant ? fixed : pick(rng);
          if (wide)
            reinterpret_cast<uint16_t*>(v.data())[i] = uint16_t(x);
          else
            v.data()[i] = uint8_t(x);
        }
        v.finalize_statistics();
        double lo = 1e300, hi = -1e300;
        for (size_t i = 0; i < size_t(v.voxel_count()); ++i) {
          lo = std::min(lo, v.stored(i));
          hi = std::max(hi, v.stored(i));
        }
        EXPECT_EQ(v.min_value, lo + v.value_offset);
        EXPECT_EQ(v.max_value, hi + v.value_offset);
        std::vector<uint64_t> want(Volume::kHistogramBins, 0);
        const double scale = hi > lo ? Volume::kHistogramBins / (hi - lo) : 0.0;
        for (size_t i = 0; i < size_t(v.voxel_count()); ++i)
          ++want[size_t(std::clamp(int((v.stored(i) - lo) * scale), 0, Volume::kHistogramBins - 1))];
        EXPECT_EQ(v.histogram, want) << to_string(t) << " " << d[0] << "x" << d[1] << "x" << d[2];
      }
}

TEST(VolumeIo, ResolveInRootsRefusesTraversal) {
  test::TempDir dir;
  fs::create_directories(dir / "data");
  test::write_file(dir / "data" / "v.nrrd", "x");
  test::write_file(dir / "secret.nrrd", "x");
  std::vector<fs::path> roots = {dir / "data"};
  EXPECT_EQ(resolve_in_roots("v.nrrd", roots), fs::canonical(dir / "data" / "v.nrrd"));
  EXPECT_THROW(resolve_in_roots("../secret.nrrd", roots), VolumeError);
  EXPECT_THROW(resolve_in_roots(dir / "secret.nrrd", roots), VolumeError);
  EXPECT_THROW(resolve_in_roots("missing.nrrd", roots), VolumeError);
  fs::create_symlink(dir / "secret.nrrd", dir / "data" / "link.nrrd");
  EXPECT_THROW(resolve_in_roots("link.nrrd", roots), VolumeError);
  try {
    resolve_in_roots("../secret.nrrd", roots);
  } catch (const VolumeError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the configured data directories"), std::string::npos);
  }
}

}  // namespace
