// NRRD by the format's rules (teem's): the rows of an outside NRRD test set, each written here
// byte for byte: a 30^3 int16 ball (range 0..257) in every encoding, with line and byte skips,
// detached single, LIST and %d data files, and the refusals (size mismatch with both numbers, a
// byte skip below -1, bad text and hex, a bzip2 bomb stopped early).
#include <bzlib.h>
#include <gtest/gtest.h>
#include <zlib.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/volume_io.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;
using test::expect_refused;

namespace {

constexpr int kN = 30;

// The ball: 257 at the centre falling to 0 at radius 13 and beyond.
std::vector<int16_t> ball() {
  std::vector<int16_t> v(size_t(kN) * kN * kN);
  for (int z = 0; z < kN; ++z)
    for (int y = 0; y < kN; ++y)
      for (int x = 0; x < kN; ++x) {
        const double r = std::sqrt(double((x - 15) * (x - 15) + (y - 15) * (y - 15) + (z - 15) * (z - 15)));
        v[size_t((z * kN + y) * kN + x)] = int16_t(std::max(0.0, 257.0 - r * 257.0 / 13.0));
      }
  return v;
}

std::string bytes_of(const std::vector<int16_t>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * 2);
}

std::string gzip(const std::string& in) {
  z_stream z{};
  deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
  std::string out(deflateBound(&z, uLong(in.size())) + 64, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(in.data()));
  z.avail_in = uInt(in.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = uInt(out.size());
  EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

std::string bzip2(const std::string& in) {
  std::string out(in.size() + in.size() / 100 + 700, '\0');
  unsigned n = unsigned(out.size());
  EXPECT_EQ(BZ2_bzBuffToBuffCompress(out.data(), &n, const_cast<char*>(in.data()), unsigned(in.size()), 9, 0, 0),
            BZ_OK);
  out.resize(n);
  return out;
}

std::string hex(const std::string& in) {
  static const char* d = "0123456789abcdef";
  std::string out;
  for (size_t i = 0; i < in.size(); ++i) {
    out += d[uint8_t(in[i]) >> 4];
    out += d[uint8_t(in[i]) & 15];
    out += (i % 32 == 31) ? '\n' : ' ';
  }
  return out;
}

std::string text(const std::vector<int16_t>& v) {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i)
    out += std::to_string(v[i]) + ((i % kN == kN - 1) ? "\n" : (i % 2 ? ", " : " "));
  return out;
}

const std::string kFields = "NRRD0004\ntype: int16\ndimension: 3\nsizes: 30 30 30\nendian: little\n";

// Loads `file` and checks it holds the ball.
void expect_ball(const fs::path& file, LoadOptions opt = {}) {
  const Volume v = load_volume(file, opt);
  ASSERT_EQ(v.dims(), (Dims{kN, kN, kN}));
  EXPECT_EQ(v.min_value, 0);
  EXPECT_EQ(v.max_value, 257);
  const auto want = ball();
  // int16 is stored shifted by 32768 as uint16 (storage_offset).
  const auto* got = reinterpret_cast<const uint16_t*>(v.data());
  for (size_t i = 0; i < want.size(); ++i)
    if (int(got[i]) - 32768 != want[i]) return ADD_FAILURE() << file << ": voxel " << i << " differs";
}

// A 352-byte NIfTI-like header before the voxels, gzipped as one stream (a .nii.gz).
std::string nii_gz() { return gzip(std::string(352, '\x5c') + bytes_of(ball())); }

}  // namespace

TEST(NrrdConformance, EveryEncodingReadsTheBall) {
  test::TempDir d;
  const std::string raw = bytes_of(ball());
  test::write_file(d / "raw.nrrd", kFields + "encoding: raw\n\n" + raw);
  test::write_file(d / "gz.nrrd", kFields + "encoding: gzip\n\n" + gzip(raw));
  test::write_file(d / "gz2.nrrd", kFields + "encoding: gz\n\n" + gzip(raw));
  test::write_file(d / "bz.nrrd", kFields + "encoding: bzip2\n\n" + bzip2(raw));
  test::write_file(d / "bz2.nrrd", kFields + "encoding: bz2\n\n" + bzip2(raw));
  test::write_file(d / "hex.nrrd", kFields + "encoding: hex\n\n" + hex(raw));
  for (const char* t : {"txt", "text", "ascii"})
    test::write_file(d / (std::string(t) + ".nrrd"), kFields + "encoding: " + t + "\n\n" + text(ball()));
  for (const char* f : {"raw", "gz", "gz2", "bz", "bz2", "hex", "txt", "text", "ascii"})
    expect_ball(d / (std::string(f) + ".nrrd"));
}

TEST(NrrdConformance, ByteSkipMinusOneIsTheLastBytesOfTheDecodedData) {
  test::TempDir d;
  test::write_file(d / "ball.nii.gz", nii_gz());
  test::write_file(d / "skip.nhdr", kFields + "encoding: gzip\nbyte skip: -1\ndata file: ball.nii.gz\n");
  expect_ball(d / "skip.nhdr");
  // The same without the skip: the header's 352 bytes are too many, said with both numbers.
  test::write_file(d / "noskip.nhdr", kFields + "encoding: gzip\ndata file: ball.nii.gz\n");
  expect_refused(d / "noskip.nhdr", "holds 54352 bytes, the volume needs 54000 (352 too many");
  // A positive skip is in the decoded data for gzip and bzip2.
  test::write_file(d / "pos.nhdr", kFields + "encoding: gzip\nbyte skip: 352\ndata file: ball.nii.gz\n");
  expect_ball(d / "pos.nhdr");
  test::write_file(d / "ball.bz2", bzip2(std::string(352, 'h') + bytes_of(ball())));
  test::write_file(d / "bz.nhdr", kFields + "encoding: bzip2\nbyte skip: -1\ndata file: ball.bz2\n");
  expect_ball(d / "bz.nhdr");
  // Raw, attached and detached; text (the last values); hex.
  test::write_file(d / "raw.nrrd", kFields + "encoding: raw\nbyte skip: -1\n\n" + "junk" + bytes_of(ball()));
  expect_ball(d / "raw.nrrd");
  test::write_file(d / "t.txt", "7 7 7\n" + text(ball()));
  test::write_file(d / "t.nhdr", kFields + "encoding: ascii\nbyte skip: -1\ndata file: t.txt\n");
  expect_ball(d / "t.nhdr");
  test::write_file(d / "h.hex", "00ff " + hex(bytes_of(ball())));
  test::write_file(d / "h.nhdr", kFields + "encoding: hex\nbyte skip: -1\ndata file: h.hex\n");
  expect_ball(d / "h.nhdr");
}

TEST(NrrdConformance, OnlyMinusOneIsANegativeByteSkip) {
  test::TempDir d;
  test::write_file(d / "ball.nii.gz", nii_gz());
  test::write_file(d / "m5.nhdr", kFields + "encoding: gzip\nbyte skip: -5\ndata file: ball.nii.gz\n");
  expect_refused(d / "m5.nhdr", "byte skip -5: the only negative byte skip NRRD allows is -1");
}

TEST(NrrdConformance, LineSkipSkipsLinesOfTheFileBeforeDecoding) {
  test::TempDir d;
  test::write_file(d / "ball.gz", "line one\nline two\n\nfour\n" + gzip(bytes_of(ball())));
  test::write_file(d / "ls.nhdr", kFields + "encoding: gzip\nline skip: 4\ndata file: ball.gz\n");
  expect_ball(d / "ls.nhdr");
  test::write_file(d / "ball.raw", "a\nb\n" + std::string(10, 'x') + bytes_of(ball()));
  test::write_file(d / "lsr.nhdr", kFields + "encoding: raw\nline skip: 2\nbyte skip: 10\ndata file: ball.raw\n");
  expect_ball(d / "lsr.nhdr");
  // Attached: the lines after the header's blank line.
  test::write_file(d / "att.nrrd", kFields + "encoding: raw\nline skip: 1\n\n" + "skipped\n" + bytes_of(ball()));
  expect_ball(d / "att.nrrd");
  test::write_file(d / "short.nhdr", kFields + "encoding: gzip\nline skip: 40\ndata file: ball.gz\n");
  expect_refused(d / "short.nhdr", "line skip 40: the file ends after");
}

TEST(NrrdConformance, ListAndPatternFilesEachTakeTheSkips) {
  test::TempDir d;
  const std::string raw = bytes_of(ball());
  const size_t slab = raw.size() / 3;
  std::string list;
  for (int i = 0; i < 3; ++i) {  // three slabs of 10 slices, each after a 16-byte header, gzipped
    test::write_file(d / ("slab" + std::to_string(i) + ".gz"), gzip(std::string(16, '#') + raw.substr(i * slab, slab)));
    list += "slab" + std::to_string(i) + ".gz\n";
  }
  test::write_file(d / "list.nhdr", kFields + "encoding: gzip\nbyte skip: 16\ndata file: LIST 3\n" + list);
  expect_ball(d / "list.nhdr");
  test::write_file(d / "pattern.nhdr", kFields + "encoding: gzip\nbyte skip: -1\ndata file: slab%d.gz 0 2 1 3\n");
  expect_ball(d / "pattern.nhdr");
  // A subdimension that asks for other files than named is refused with both counts.
  test::write_file(d / "sub.nhdr", kFields + "encoding: gzip\nbyte skip: 16\ndata file: slab%d.gz 0 2 1 2\n");
  expect_refused(d / "sub.nhdr", "asks for 30 files, the header names 3");
  // Files that cannot hold equal shares.
  test::write_file(d / "odd.nhdr", kFields + "encoding: gzip\ndata file: slab%d.gz 0 6 1\n");
  expect_refused(d / "odd.nhdr", "7 data files cannot hold equal shares");
}

TEST(NrrdConformance, ADecodedSizeThatDoesNotMatchIsRefusedWithBothNumbers) {
  test::TempDir d;
  const std::string raw = bytes_of(ball());
  test::write_file(d / "long.nrrd", kFields + "encoding: raw\n\n" + raw + "xx");
  expect_refused(d / "long.nrrd",
                 "the file holds 54002 data bytes after its skips, the header long.nrrd promises 54000");
  test::write_file(d / "short.nrrd", kFields + "encoding: raw\n\n" + raw.substr(10));
  expect_refused(d / "short.nrrd", "promises 54000 data bytes here, the file holds 53990");
  test::write_file(d / "gzshort.nrrd", kFields + "encoding: gzip\n\n" + gzip(raw.substr(2)));
  expect_refused(d / "gzshort.nrrd", "holds 53998 bytes, the volume needs 54000");
  test::write_file(d / "bzlong.nrrd", kFields + "encoding: bzip2\n\n" + bzip2(raw + raw));
  expect_refused(d / "bzlong.nrrd", "holds 108000 bytes, the volume needs 54000 (54000 too many");
  test::write_file(d / "txtlong.nrrd", kFields + "encoding: txt\n\n" + text(ball()) + " 5");
  expect_refused(d / "txtlong.nrrd", "holds 54002 bytes (as int16), the volume needs 54000");
}

TEST(NrrdConformance, BadTextAndHexAreRefusedWhereTheyAre) {
  test::TempDir d;
  const std::string f = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n";
  test::write_file(d / "big.nrrd", f + "encoding: txt\n\n1 2 3 256 5 6 7 8\n");
  expect_refused(d / "big.nrrd", "value 3 (256) does not fit uint8");
  test::write_file(d / "frac.nrrd", f + "encoding: txt\n\n1 2 3 4.5 5 6 7 8\n");
  expect_refused(d / "frac.nrrd", "value 3 (4.5) does not fit uint8");
  test::write_file(d / "word.nrrd", f + "encoding: txt\n\n1 2 three 4 5 6 7 8\n");
  expect_refused(d / "word.nrrd", "value 2 'three' is not a number");
  test::write_file(d / "odd.nrrd", f + "encoding: hex\n\n0102030405060708a\n");
  expect_refused(d / "odd.nrrd", "an odd number of hex digits");
  test::write_file(d / "g.nrrd", f + "encoding: hex\n\n01020g0405060708\n");
  expect_refused(d / "g.nrrd", "is not a hex digit");
  test::write_file(d / "lzma.nrrd", f + "encoding: lzma\n\n");
  expect_refused(d / "lzma.nrrd", "unsupported encoding 'lzma' (NRRD's: raw, txt, hex, gzip, bzip2)");
  // Floats as text: read as float32, text spellings of numbers included.
  test::write_file(d / "f.nrrd",
                   "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: text\n\n-1.5 +2 3e2 0.25,4 5 6 7\n");
  const Volume v = load_volume(d / "f.nrrd");
  EXPECT_FLOAT_EQ(v.min_value, -1.5f);
  EXPECT_FLOAT_EQ(v.max_value, 300.0f);
}

TEST(NrrdConformance, ABzip2BombIsStoppedEarly) {
  // 64 MiB of zeros in a few hundred bytes, for a 2x2x2 volume: refused before it is all decoded,
  // with or without a byte skip of -1 (which counts the decoded data first).
  test::TempDir d;
  const std::string bomb = bzip2(std::string(size_t(64) << 20, '\0'));
  for (const auto& [skip, why] : {std::pair<std::string, std::string>{"", "the decoded data holds more than"},
                                  {"byte skip: -1\n", "byte skip -1: the decoded data runs past"}}) {
    test::write_file(d / "bomb.nrrd",
                     "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: bzip2\n" + skip + "\n" + bomb);
    const auto t0 = std::chrono::steady_clock::now();
    expect_refused(d / "bomb.nrrd", why);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0) << skip;
  }
}

TEST(NrrdConformance, EveryOtherRefusalSaysWhy) {
  test::TempDir d;
  const std::string f = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\n";
  const std::string eight = std::string(8, '\x07');
  test::write_file(d / "s0.raw", eight);
  test::write_file(d / "s1.raw", eight);
  const std::pair<std::string, std::string> cases[] = {
      {f + "encoding: raw\nline skip: -1\n\n" + eight, "line skip must be >= 0"},
      {f + "encoding: raw\ndata file: s%d.raw 0 1 1 4\n", "subdimension 4 is not in 1..3"},
      {"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 3\nencoding: raw\ndata file: s%d.raw 0 1 1 3\n",
       "2 slabs cannot split the slowest axis' 3 evenly"},
      {f + "encoding: bzip2\n\nBZh9 this is not bzip2 at all", "bzip2 stream corrupt"},
      {f + "encoding: bzip2\n\n" + bzip2(eight).substr(0, 30), "truncated: the bzip2 stream does not end"},
      {f + "encoding: txt\n\n1 2 3 " + std::string(70, '4') + " 5 6 7 8\n", "value 3 is longer than 64 characters"},
  };
  for (size_t k = 0; k < std::size(cases); ++k) {
    const fs::path file = d / ("r" + std::to_string(k) + ".nhdr");
    test::write_file(file, cases[k].first);
    expect_refused(file, cases[k].second);
  }
}

TEST(NrrdConformance, ARegionOfAnyEncodingIsTheCropOfTheWhole) {
  // An MPI rank's brick: the same voxels as the whole file's, for a decoded (bzip2, text) payload.
  test::TempDir d;
  test::write_file(d / "ball.bz2", bzip2(std::string(352, 'h') + bytes_of(ball())));
  test::write_file(d / "bz.nhdr", kFields + "encoding: bzip2\nbyte skip: -1\ndata file: ball.bz2\n");
  test::write_file(d / "t.nrrd", kFields + "encoding: txt\n\n" + text(ball()));
  for (const char* f : {"bz.nhdr", "t.nrrd"}) {
    LoadOptions o;
    o.region = VoxelRegion{{3, 7, 11}, {20, 25, 29}};
    const Volume r = load_volume(d / f, o);
    const Volume whole = load_volume(d / f);
    ASSERT_EQ(r.dims(), (Dims{17, 18, 18})) << f;
    const auto* a = reinterpret_cast<const uint16_t*>(r.data());
    const auto* b = reinterpret_cast<const uint16_t*>(whole.data());
    for (int z = 0; z < 18; ++z)
      for (int y = 0; y < 18; ++y)
        for (int x = 0; x < 17; ++x) ASSERT_EQ(a[(z * 18 + y) * 17 + x], b[((z + 11) * kN + y + 7) * kN + x + 3]) << f;
  }
}
