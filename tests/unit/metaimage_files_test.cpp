// MetaImage as ITK writes it: ElementDataFile = LIST and printf patterns of slice
// files (HeaderSize in each), and MET_DOUBLE and the 32/64-bit integer types converted by the
// stated rule (metaimage_wide.cpp), refused when the values do not fit.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "core/volume_io.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;
using test::expect_refused;

namespace {

template <typename T>
std::string bytes_of(const std::vector<T>& v, bool big_endian = false) {
  std::string out(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  if (big_endian)
    for (size_t i = 0; i < v.size(); ++i)
      std::reverse(out.begin() + long(i * sizeof(T)), out.begin() + long((i + 1) * sizeof(T)));
  return out;
}

std::vector<uint16_t> ramp(size_t n) {
  std::vector<uint16_t> v(n);
  for (size_t i = 0; i < n; ++i) v[i] = uint16_t(i * 37 % 65521);
  return v;
}

const std::string kHead = "ObjectType = Image\nNDims = 3\nDimSize = 4 3 5\nElementSpacing = 1 1 2\n";

}  // namespace

TEST(MetaImageFiles, ListAndPatternOfSlicesReadAsOneVolume) {
  test::TempDir d;
  const auto v = ramp(4 * 3 * 5);
  const std::string raw = bytes_of(v);
  std::string list;
  for (int z = 0; z < 5; ++z) {  // one slice a file, each after a 12-byte header of its own
    test::write_file(d / ("s" + std::to_string(z + 1) + ".raw"), std::string(12, 'H') + raw.substr(size_t(z) * 24, 24));
    list += "s" + std::to_string(z + 1) + ".raw\n";
  }
  const std::string type = "ElementType = MET_USHORT\nHeaderSize = 12\n";
  test::write_file(d / "list.mhd", kHead + type + "ElementDataFile = LIST 2D\n" + list);
  test::write_file(d / "pattern.mhd", kHead + type + "ElementDataFile = s%d.raw 1 5 1 2\n");
  test::write_file(d / "last.mhd",
                   kHead + "ElementType = MET_USHORT\nHeaderSize = -1\nElementDataFile = s%d.raw 1 5 1\n");
  for (const char* f : {"list.mhd", "pattern.mhd", "last.mhd"}) {
    const Volume got = load_volume(d / f);
    ASSERT_EQ(got.dims(), (Dims{4, 3, 5})) << f;
    EXPECT_EQ(std::memcmp(got.data(), v.data(), raw.size()), 0) << f;
  }
  // A file count other than the slices, or a slab dimension that asks for other files: refused.
  test::write_file(d / "few.mhd", kHead + type + "ElementDataFile = s%d.raw 1 4 1\n");
  expect_refused(d / "few.mhd", "asks for 5 files, the header names 4");
  test::write_file(d / "rows.mhd", kHead + type + "ElementDataFile = LIST 1D\n" + list);
  expect_refused(d / "rows.mhd", "asks for 15 files, the header names 5");
  // A header size below -1, a file dimension MetaImage has not, and -1 on compressed data.
  test::write_file(d / "hs.mhd",
                   kHead + "ElementType = MET_USHORT\nHeaderSize = -3\nElementDataFile = s%d.raw 1 5 1\n");
  expect_refused(d / "hs.mhd", "HeaderSize -3: -1 or >= 0");
  test::write_file(d / "dim.mhd", kHead + type + "ElementDataFile = s%d.raw 1 5 1 4D\n");
  expect_refused(d / "dim.mhd", "a file dimension of 4D (need 1, 2 or 3)");
  test::write_file(d / "zl.mhd", kHead +
                                     "ElementType = MET_USHORT\nCompressedData = True\nHeaderSize = -1\n"
                                     "ElementDataFile = s%d.raw 1 5 1\n");
  expect_refused(d / "zl.mhd", "a header size of -1 (the data at the end of the file) needs raw data");
  test::write_file(d / "gone.mhd", kHead + type + "ElementDataFile = LIST\ns1.raw\ns2.raw\ns3.raw\ns4.raw\ns9.raw\n");
  expect_refused(d / "gone.mhd", "no such file");
  test::write_file(d / "long.mhd", kHead + type + "ElementDataFile = s%d.raw 1 5 1 2\n");
  test::write_file(d / "s3.raw", std::string(12, 'H') + raw.substr(48, 24) + "x");
  expect_refused(d / "long.mhd",
                 "the file holds 25 data bytes after its skips, the header long.mhd promises 24 (1 too "
                 "many; 'HeaderSize = -1' reads the last bytes)");
}

TEST(MetaImageFiles, DoublesBecomeFloat32AndTooLargeOnesAreRefused) {
  test::TempDir d;
  std::vector<double> v(60);
  for (size_t i = 0; i < v.size(); ++i) v[i] = double(i) * 0.25 - 3.0;
  test::write_file(d / "d.raw", bytes_of(v, true));
  test::write_file(d / "d.mhd",
                   kHead + "ElementType = MET_DOUBLE\nElementByteOrderMSB = True\nElementDataFile = d.raw\n");
  const Volume got = load_volume(d / "d.mhd");
  EXPECT_EQ(got.source_type(), SourceType::F32);
  EXPECT_DOUBLE_EQ(got.min_value, -3.0);
  EXPECT_DOUBLE_EQ(got.max_value, 59 * 0.25 - 3.0);
  EXPECT_FLOAT_EQ(reinterpret_cast<const float*>(got.data())[7], 7 * 0.25f - 3.0f);
  v[5] = 1e300;
  test::write_file(d / "big.raw", bytes_of(v));
  test::write_file(d / "big.mha", kHead + "ElementType = MET_DOUBLE\nElementDataFile = LOCAL\n" + bytes_of(v));
  expect_refused(d / "big.mha", "do not fit in float32");
}

TEST(MetaImageFiles, WideIntegersTakeTheNarrowestKeptType) {
  test::TempDir d;
  auto load_ints = [&](const std::string& type, const std::vector<int64_t>& values, int bytes) {
    std::string data;
    for (int64_t x : values) {
      if (bytes == 4) {
        const int32_t y = int32_t(x);
        data.append(reinterpret_cast<const char*>(&y), 4);
      } else {
        data.append(reinterpret_cast<const char*>(&x), 8);
      }
    }
    test::write_file(d / "i.mha", kHead + "ElementType = " + type + "\nElementDataFile = LOCAL\n" + data);
    return load_volume(d / "i.mha");
  };
  std::vector<int64_t> labels(60, 0);
  labels[3] = 200;
  EXPECT_EQ(load_ints("MET_INT", labels, 4).source_type(), SourceType::U8);
  labels[4] = -5;
  EXPECT_EQ(load_ints("MET_LONG", labels, 4).source_type(), SourceType::I16);  // -5..200: not int8
  labels[4] = 40000;
  EXPECT_EQ(load_ints("MET_UINT", labels, 4).source_type(), SourceType::U16);
  labels[5] = -1000;
  const Volume f = load_ints("MET_LONG_LONG", labels, 8);  // -1000..40000: exact in float32
  EXPECT_EQ(f.source_type(), SourceType::F32);
  EXPECT_DOUBLE_EQ(f.min_value, -1000);
  EXPECT_DOUBLE_EQ(f.max_value, 40000);
  labels[6] = (int64_t(1) << 24) + 1;
  try {
    load_ints("MET_LONG_LONG", labels, 8);
    ADD_FAILURE() << "2^24 + 1 loaded";
  } catch (const VolumeError& e) {
    EXPECT_NE(std::string(e.what()).find("not exact in float32"), std::string::npos) << e.what();
  }
}

TEST(MetaImageFiles, ARegionOfAConvertedVolumeIsTheCropOfTheWhole) {
  test::TempDir d;
  std::vector<int32_t> v(60);
  for (size_t i = 0; i < v.size(); ++i) v[i] = int32_t(i * 1000);
  test::write_file(d / "r.mha", kHead + "ElementType = MET_INT\nElementDataFile = LOCAL\n" + bytes_of(v));
  LoadOptions o;
  o.region = VoxelRegion{{1, 1, 2}, {3, 3, 5}};
  const Volume r = load_volume(d / "r.mha", o);
  ASSERT_EQ(r.dims(), (Dims{2, 2, 3}));
  EXPECT_EQ(r.source_type(), SourceType::U16);  // 0..59000
  EXPECT_EQ(r.region_lo, (Dims{1, 1, 2}));
  EXPECT_EQ(reinterpret_cast<const uint16_t*>(r.data())[0], ((2 * 3 + 1) * 4 + 1) * 1000);
  EXPECT_EQ(reinterpret_cast<const uint16_t*>(r.data())[11], ((4 * 3 + 2) * 4 + 2) * 1000);
}
