// Each bad file is refused with one error naming the file and the
// reason, before any allocation beyond the limit.
#include <gtest/gtest.h>
#include <zlib.h>

#include "core/volume_io.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;

namespace {

// Expects load_volume(file) to throw a VolumeError whose text names `file` and contains `reason`.
void expect_refused(const fs::path& file, const std::string& reason, LoadOptions opt = {}) {
  try {
    load_volume(file, opt);
    ADD_FAILURE() << file << " loaded, expected refusal: " << reason;
  } catch (const VolumeError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.filename().string()), std::string::npos) << what;
    EXPECT_NE(what.find(reason), std::string::npos) << "'" << what << "' lacks '" << reason << "'";
    EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
  }
}

// A NRRD header; the blank line ends it, attached data follows.
std::string nrrd(const std::string& fields) { return "NRRD0004\n" + fields + "\n\n"; }

TEST(Refusal, MissingFile) {
  test::TempDir d;
  expect_refused(d / "nothing.nrrd", "no such file");
  test::write_file(d / "h.nhdr", nrrd("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: gone.raw"));
  expect_refused(d / "h.nhdr", "no such file");
}

TEST(Refusal, TruncatedData) {
  test::TempDir d;
  test::write_file(d / "t.nrrd",
                   nrrd("type: uint16\ndimension: 3\nsizes: 4 4 4\nencoding: raw") + std::string(100, 'x'));
  expect_refused(d / "t.nrrd", "truncated");
  test::write_file(d / "t.raw", std::string(7, 'x'));
  test::write_file(d / "t.raw.json", R"({"dims":[2,2,2],"dtype":"uint8"})");
  expect_refused(d / "t.raw", "truncated");
  test::write_file(d / "t.mhd", "NDims = 3\nDimSize = 2 2 2\nElementType = MET_FLOAT\nElementDataFile = t.raw\n");
  expect_refused(d / "t.mhd", "truncated");
}

TEST(Refusal, TruncatedGzip) {
  test::TempDir d;
  std::string payload(1000, 'a');
  uLongf len = compressBound(uLong(payload.size()));
  std::string z(len, '\0');
  compress2(reinterpret_cast<Bytef*>(z.data()), &len, reinterpret_cast<const Bytef*>(payload.data()),
            uLong(payload.size()), 6);
  z.resize(len);
  // A valid zlib stream of 1000 bytes where the header promises 8000.
  test::write_file(
      d / "short.mha",
      "NDims = 3\nDimSize = 20 20 20\nElementType = MET_UCHAR\nCompressedData = True\nElementDataFile = LOCAL\n" + z);
  expect_refused(d / "short.mha", "truncated");
}

TEST(Refusal, HugeOrOverflowingSizesRefusedBeforeAllocation) {
  test::TempDir d;
  test::write_file(d / "o.nrrd",
                   nrrd("type: float\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\nencoding: raw"));
  expect_refused(d / "o.nrrd", "overflow");
  // 2^33 voxels: over the default limit of 2^32; a small file, so nothing may be allocated.
  test::write_file(d / "big.nrrd", nrrd("type: uint8\ndimension: 3\nsizes: 2048 2048 2048\nencoding: raw") + "xx");
  expect_refused(d / "big.nrrd", "exceeds the limit");
  LoadOptions small;
  small.max_voxels = 1000;
  test::write_file(d / "s.nrrd",
                   nrrd("type: uint8\ndimension: 3\nsizes: 11 10 10\nencoding: raw") + std::string(1100, 'x'));
  expect_refused(d / "s.nrrd", "exceeds the limit of 1000", small);
  // Within the limit but the file is short: refused as truncated, not allocated.
  test::write_file(d / "p.raw", "xx");
  test::write_file(d / "p.raw.json", R"({"dims":[1000,1000,1000],"dtype":"float32"})");
  expect_refused(d / "p.raw", "truncated");
}

TEST(Refusal, UnknownTypeOrEncoding) {
  test::TempDir d;
  test::write_file(d / "ty.nrrd", nrrd("type: double\ndimension: 3\nsizes: 2 2 2\nencoding: raw"));
  expect_refused(d / "ty.nrrd", "unsupported voxel type 'double'");
  test::write_file(d / "en.nrrd", nrrd("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: lzma"));
  expect_refused(d / "en.nrrd", "unsupported encoding 'lzma'");
  test::write_file(d / "ty.mhd", "NDims = 3\nDimSize = 2 2 2\nElementType = MET_COMPLEX\nElementDataFile = x.raw\n");
  expect_refused(d / "ty.mhd", "unsupported voxel type");
  test::write_file(d / "ty.raw", "12345678");
  test::write_file(d / "ty.raw.json", R"({"dims":[2,2,2],"dtype":"complex64"})");
  expect_refused(d / "ty.raw", "unsupported voxel type");
  test::write_file(d / "what.vol", "x");
  expect_refused(d / "what.vol", "unknown volume format");
}

TEST(Refusal, ZeroDims) {
  test::TempDir d;
  test::write_file(d / "z.nrrd", nrrd("type: uint8\ndimension: 3\nsizes: 4 0 4\nencoding: raw"));
  expect_refused(d / "z.nrrd", "every size must be >= 1");
  test::write_file(d / "n.raw", "");
  test::write_file(d / "n.raw.json", R"({"dims":[2,-1,2],"dtype":"uint8"})");
  expect_refused(d / "n.raw", "every size must be >= 1");
}

TEST(Refusal, CorruptGzip) {
  test::TempDir d;
  test::write_file(d / "nomagic.nrrd",
                   nrrd("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: gzip") + "not gzip at all");
  expect_refused(d / "nomagic.nrrd", "gzip stream corrupt");
  std::string garbage = "\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03" + std::string(64, '\xff');
  test::write_file(d / "bad.nrrd", nrrd("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: gzip") + garbage);
  expect_refused(d / "bad.nrrd", "gzip stream corrupt");
}

TEST(Refusal, NonFiniteFloatsWhenPolicyIsRefuse) {
  test::TempDir d;
  const float values[] = {1, 2, 3, std::numeric_limits<float>::quiet_NaN(), 5, 6, 7, 8};
  test::write_file(d / "nan.raw", std::string(reinterpret_cast<const char*>(values), sizeof values));
  test::write_file(d / "nan.raw.json", R"({"dims":[2,2,2],"dtype":"float32"})");
  LoadOptions opt;
  opt.nonfinite = NonFinitePolicy::Refuse;
  expect_refused(d / "nan.raw.json", "1 NaN/Inf voxels", opt);
}

TEST(Refusal, MalformedHeaders) {
  test::TempDir d;
  test::write_file(d / "magic.nrrd", "NOPE\n");
  expect_refused(d / "magic.nrrd", "not a NRRD file");
  test::write_file(d / "dim.nrrd", nrrd("type: uint8\ndimension: 2\nsizes: 2 2\nencoding: raw"));
  expect_refused(d / "dim.nrrd", "dimension 2 is not supported");
  test::write_file(
      d / "obl.nrrd",
      nrrd("type: uint8\ndimension: 3\nsizes: 2 2 2\nspace directions: (1,1,0) (0,1,0) (0,0,1)\nencoding: raw") +
          "12345678");
  expect_refused(d / "obl.nrrd", "not axis-aligned");
  test::write_file(d / "nosizes.nrrd", nrrd("type: uint8\ndimension: 3\nencoding: raw"));
  expect_refused(d / "nosizes.nrrd", "missing field 'sizes'");
  test::write_file(d / "j.raw", "12345678");
  test::write_file(d / "j.raw.json", "{\"dims\": [2,2,2], \"dtype\": ");
  expect_refused(d / "j.raw", "invalid JSON");
  test::write_file(d / "k.raw", "12345678");
  test::write_file(d / "k.raw.json", R"({"dims":[2,2,2],"dtype":"uint8","spacings":[1,1,1]})");
  expect_refused(d / "k.raw", "unknown key 'spacings'");
  test::write_file(d / "nosidecar.raw", "12345678");
  expect_refused(d / "nosidecar.raw", "needs a JSON sidecar");
  test::write_file(d / "sp.nrrd",
                   nrrd("type: uint8\ndimension: 3\nsizes: 2 2 2\nspacings: 1 0 1\nencoding: raw") + "12345678");
  expect_refused(d / "sp.nrrd", "spacing must be finite and > 0");
}

}  // namespace
