// The security rules held function by function (the net tests hold them against the real server,
// tests/net/test_audit_*.py): UTF-8 cleaning, errors without server paths, reads confined to the
// data directories, uploads as one file, chunk decoding charged to the memory budget, the Host
// allow-list, constant-time tokens, the static file list.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "chunked/chunk_codec.h"
#include "core/file_roots.h"
#include "core/public_text.h"
#include "core/utf8.h"
#include "net/access.h"
#include "net/http_text.h"
#include "net/static_files.h"
#include "session/data_listing.h"
#include "session/upload_formats.h"
#include "session/upload_store.h"
#include "unit/chunked_test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;
using peakcast::test::write_file;
using peakcast::test::write_json;

TEST(Utf8, CleanCutsAtCharactersAndReplacesBadBytes) {
  EXPECT_TRUE(valid_utf8("héllo データ"));
  EXPECT_FALSE(valid_utf8("\xff"));
  EXPECT_FALSE(valid_utf8("\xc3"));          // cut in the middle of é
  EXPECT_FALSE(valid_utf8("\xed\xa0\x80"));  // a surrogate
  EXPECT_FALSE(valid_utf8("\xc0\xaf"));      // an overlong '/'
  EXPECT_EQ(clean_utf8("a\xff"
                       "b"),
            "a\xEF\xBF\xBD"
            "b");
  const std::string e = "\xc3\xa9";                                           // é, two bytes
  EXPECT_EQ(clean_utf8(std::string(63, 'a') + e, 64), std::string(63, 'a'));  // not half of é
  std::string name;
  for (int i = 0; i < 23; ++i) name += "データ";  // 9 bytes each: 207 bytes
  const std::string cut = clean_upload_name(name + ".raw");
  EXPECT_TRUE(valid_utf8(cut));
  EXPECT_LE(cut.size(), limits::kMaxUploadNameLength);
  EXPECT_EQ(cut.size() % 3, 0u);  // whole characters only
  EXPECT_EQ(clean_upload_name("\xff"), "\xEF\xBF\xBD");
  EXPECT_EQ(clean_upload_name("\x01\x02"), "upload");
}

TEST(Utf8, JsonTextNeverThrowsOnBadBytes) {
  const nlohmann::json j = {{"message", "type \xff\xfe"}};
  EXPECT_THROW((void)j.dump(), nlohmann::json::type_error);  // what ended the process before
  const std::string text = json_text(j);
  EXPECT_TRUE(valid_utf8(text));
  EXPECT_EQ(nlohmann::json::parse(text)["message"], "type \xEF\xBF\xBD\xEF\xBF\xBD");
}

TEST(PublicText, ServerPathsBecomeTheirLastComponent) {
  EXPECT_EQ(public_text("/etc/passwd: not a volume"), "passwd: not a volume");
  EXPECT_EQ(public_text("cannot open '/proc/self/cmdline'"), "cannot open 'cmdline'");
  EXPECT_EQ(public_text("/api/volumes/x is not an API route"), "/api/volumes/x is not an API route");
  EXPECT_EQ(public_text("em/stack.nrrd: truncated"), "em/stack.nrrd: truncated");
  EXPECT_EQ(public_text("filesystem error: cannot canonicalize: Too many levels [/tmp/a/v.zarr/.zarray]"),
            "filesystem error: cannot canonicalize: Too many levels [.zarray]");
  EXPECT_TRUE(valid_utf8(public_text("bad \xff byte at /usr/x")));
  EXPECT_LE(public_text(std::string(10000, 'x')).size(), kMaxPublicTextBytes);
}

class Confined : public ::testing::Test {
 protected:
  test::TempDir tmp;
  fs::path data() { return tmp / "data"; }
  fs::path outside() { return tmp / "outside"; }
  void SetUp() override {
    fs::create_directories(data());
    fs::create_directories(outside());
  }
};

TEST_F(Confined, DetachedDataFileOutsideIsRefused) {
  write_file(outside() / "secret.raw", std::string(8, 'x'));
  write_file(data() / "abs.nhdr", "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: " +
                                      (outside() / "secret.raw").string() + "\n\n");
  write_file(data() / "up.nhdr",
             "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: ../outside/secret.raw\n\n");
  EXPECT_EQ(test::refusal(data() / "abs.nhdr"), "");  // not confined: a command-line tool reads what it is told
  file_roots::Scope scope({data()});
  EXPECT_NE(test::refusal(data() / "abs.nhdr").find("outside the data directories"), std::string::npos);
  EXPECT_NE(test::refusal(data() / "up.nhdr").find("outside the data directories"), std::string::npos);
}

TEST_F(Confined, ChunkOrLevelLinkedOutIsRefused) {
  const fs::path z = data() / "v.zarr";
  fs::create_directories(z);
  write_json(z / ".zarray", {{"zarr_format", 2},
                             {"shape", {2, 2, 2}},
                             {"chunks", {2, 2, 2}},
                             {"dtype", "|u1"},
                             {"compressor", nullptr},
                             {"fill_value", 0},
                             {"order", "C"},
                             {"filters", nullptr}});
  write_file(outside() / "chunk", std::string(8, '\x07'));
  fs::create_symlink(outside() / "chunk", z / "0.0.0");
  EXPECT_EQ(test::refusal(z), "");
  {
    file_roots::Scope scope({data()});
    EXPECT_NE(test::refusal(z).find("outside the data directories"), std::string::npos);
  }
  // A whole level folder linked out.
  const fs::path p = data() / "p.zarr";
  fs::create_directories(p);
  write_json(p / ".zattrs", {{"multiscales",
                              {{{"version", "0.4"},
                                {"axes",
                                 {{{"name", "z"}, {"type", "space"}},
                                  {{"name", "y"}, {"type", "space"}},
                                  {{"name", "x"}, {"type", "space"}}}},
                                {"datasets", {{{"path", "0"}}}}}}}});
  fs::copy(z, outside() / "level0", fs::copy_options::recursive | fs::copy_options::copy_symlinks);
  fs::remove(outside() / "level0/0.0.0");
  write_file(outside() / "level0/0.0.0", std::string(8, '\x07'));
  fs::create_directory_symlink(outside() / "level0", p / "0");
  EXPECT_EQ(test::refusal(p), "");
  file_roots::Scope scope({data()});
  EXPECT_NE(test::refusal(p).find("outside the data directories"), std::string::npos);
}

TEST_F(Confined, SingleFileRefusesAnotherDataFileUnseen) {
  write_file(data() / "u.nrrd",
             "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n data file: /etc/passwd\n\n");
  write_file(data() / "u.mha",
             "ObjectType = Image\nComment = x\n\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n"
             "ElementDataFile\t= /nonexistent/file\n");
  LoadOptions o;
  o.single_file = true;
  for (const char* f : {"u.nrrd", "u.mha"}) {
    const std::string why = test::refusal(data() / f, o);
    EXPECT_NE(why.find("names another data file"), std::string::npos) << why;
    EXPECT_EQ(why.find("no such file"), std::string::npos) << why;  // nothing said of that path
  }
  // Its own data, attached: read.
  write_file(data() / "ok.nrrd",
             "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n" + std::string(8, 'x'));
  EXPECT_EQ(test::refusal(data() / "ok.nrrd", o), "");
}

TEST(UploadSniff, EverySpellingOfAnotherFileIsRefused) {
  test::TempDir tmp;
  const char* bodies[] = {
      "ObjectType = Image\nComment = x\n\nElementDataFile = /etc/passwd\n",
      "ObjectType = Image\nNDims = 3\nElementDataFile\t= /etc/passwd\n",
      "NRRD0004\ntype: uchar\ndata file : /etc/passwd\n\n",
      "NRRD0004\ntype: uchar\n data file: /etc/passwd\n\n",
      "NRRD0004\ntype: uchar\nDataFile: /etc/passwd\n\n",
  };
  for (const char* b : bodies) {
    write_file(tmp / "body", b);
    try {
      sniff_upload(tmp / "body", false);
      ADD_FAILURE() << "accepted: " << b;
    } catch (const UploadRefusal& r) {
      EXPECT_EQ(r.status, 415) << b;
    }
  }
}

TEST(UploadRaw, BodyMustMatchItsDimsAndEveryAxisHasTwoVoxels) {
  const auto side = raw_sidecar({{"dims", {5, 10, 10}}, {"dtype", "uint8"}}, "x.raw");
  EXPECT_NO_THROW(check_raw_body(side, 500));
  try {
    check_raw_body(side, 1000);
    ADD_FAILURE();
  } catch (const UploadRefusal& r) {
    EXPECT_EQ(r.status, 400);
    EXPECT_NE(std::string(r.what()).find("500"), std::string::npos);
    EXPECT_NE(std::string(r.what()).find("1000"), std::string::npos);
  }
  EXPECT_THROW(check_raw_body(raw_sidecar({{"dims", {1000, 1, 1}}, {"dtype", "uint8"}}, "x.raw"), 1000), UploadRefusal);
}

TEST(ChunkBudget, ChunksDecodingPastTheBudgetAreRefusedBeforeDecoding) {
  test::TempDir tmp;
  const fs::path z = tmp / "bomb.zarr";
  fs::create_directories(z);
  // 8x64x64 voxels in chunks of 2x16384x16384: one chunk decodes to 512 MiB.
  write_json(z / ".zarray", {{"zarr_format", 2},
                             {"shape", {8, 64, 64}},
                             {"chunks", {2, 16384, 16384}},
                             {"dtype", "|u1"},
                             {"compressor", nullptr},
                             {"fill_value", 0},
                             {"order", "C"},
                             {"filters", nullptr}});
  write_file(z / "0.0.0", "x");  // never read: refused from the metadata
  LoadOptions o;
  o.decode_budget_bytes = int64_t(64) << 20;
  const std::string why = test::refusal(z, o);
  EXPECT_NE(why.find("memory budget"), std::string::npos) << why;
  // A level cut into more chunks than a read may visit: refused at once.
  const fs::path p = tmp / "tiny";
  fs::create_directories(p);
  write_json(p / "info", {{"type", "image"},
                          {"data_type", "uint8"},
                          {"num_channels", 1},
                          {"scales",
                           {{{"key", "1_1_1"},
                             {"size", {4096, 4096, 1}},
                             {"resolution", {1, 1, 1}},
                             {"chunk_sizes", {{1, 1, 1}}},
                             {"encoding", "raw"},
                             {"voxel_offset", {0, 0, 0}}}}}});
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_NE(test::refusal(p).find("chunks"), std::string::npos);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 2.0);
}

// A level of a million chunks, none stored (a sparse volume, or a hostile `info`): the folder is
// listed once instead of a stat per chunk (chunked/formats.h, FolderIndex). Before, a million
// probes took ~2 µs each on the loader thread, and 16 million took 33 s.
TEST(ChunkBudget, MissingChunksCostOneListing) {
  test::TempDir tmp;
  const fs::path z = tmp / "sparse.zarr";
  fs::create_directories(z);
  write_json(z / ".zarray", {{"zarr_format", 2},
                             {"shape", {2, 1024, 512}},
                             {"chunks", {1, 1, 1}},
                             {"dtype", "|u1"},
                             {"compressor", nullptr},
                             {"fill_value", 3},
                             {"order", "C"},
                             {"filters", nullptr}});
  write_file(z / "1.1023.511", "\x09");  // the one chunk stored
  const auto t0 = std::chrono::steady_clock::now();
  const Volume v = load_volume(z);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(v.max_value, 9);
  EXPECT_EQ(v.min_value, 3);
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  EXPECT_LT(seconds, 30.0);
#else
  EXPECT_LT(seconds, 1.0);  // measured: 0.12 s for the read here
#endif
}

// Found by fuzz_chunk_codecs: a 15-byte zstd frame claiming a 64 MiB window made the decoder
// allocate it. A window larger than the chunk is refused; a frame zstd writes for the chunk reads.
TEST(ChunkBudget, ZstdWindowLargerThanTheChunkIsRefused) {
  const std::vector<uint8_t> claim = {0x28, 0xb5, 0x2f, 0xfd, 0xb0, 0x00, 0x37, 0x20, 0x04, 0xfd, 0xb0, 0x14, 0x64};
  chunked::CompressorSpec zstd;
  zstd.id = chunked::Compressor::Zstd;
  try {
    chunked::decode_chunk(zstd, claim, 13030, "chunk");
    ADD_FAILURE() << "decoded";
  } catch (const VolumeError& e) {  // refused from the frame header, before the window is allocated
    EXPECT_NE(std::string(e.what()).find("too much memory"), std::string::npos) << e.what();
  }
  std::vector<uint8_t> voxels(13030);
  for (size_t i = 0; i < voxels.size(); ++i) voxels[i] = uint8_t(i * 7);
  const auto packed = chunked::encode_chunk(zstd, voxels.data(), voxels.size(), 1);
  EXPECT_EQ(chunked::decode_chunk(zstd, packed, voxels.size(), "chunk"), voxels);
}

// Found by fuzz_chunk_codecs: a 14-byte frame with zstd v0.7's legacy magic (0xFD2FB527), whose
// decoder ignores the window cap, allocated the 64 MiB window it claims. Refused by its magic.
TEST(ChunkBudget, LegacyZstdFramesAreRefused) {
  const std::vector<uint8_t> legacy = {0x27, 0xb5, 0x2f, 0xfd, 0x00, 0x80, 0x00, 0x0e, 0x00, 0x00, 0x25, 0x00};
  chunked::CompressorSpec zstd;
  zstd.id = chunked::Compressor::Zstd;
  try {
    chunked::decode_chunk(zstd, legacy, 248, "chunk");
    ADD_FAILURE() << "decoded";
  } catch (const VolumeError& e) {
    EXPECT_NE(std::string(e.what()).find("legacy"), std::string::npos) << e.what();
  }
}

// Found by fuzz_data_listing: a folder name with a NUL byte was cut there by the system calls
// and listed the data directory's root.
TEST(Listing, FolderNameWithNulIsRefused) {
  test::TempDir tmp;
  fs::create_directories(tmp / "data/sub");
  EXPECT_NO_THROW(list_data_dir({tmp / "data"}, "sub"));
  EXPECT_THROW(list_data_dir({tmp / "data"}, std::string("\0\x08secret", 8)), VolumeError);
}

TEST(HttpText, HostAllowList) {
  using net::HostCheck;
  const HostCheck local("127.0.0.1", {"viewer.example.org"});
  for (const char* ok :
       {"127.0.0.1:8080", "localhost:8080", "LOCALHOST", "[::1]:8080", "viewer.example.org", "", "localhost."})
    EXPECT_TRUE(local.allowed(ok)) << ok;
  for (const char* no :
       {"evil.example:8080", "10.0.0.1:8080", "localhost:80:80", "local\xffhost", "viewer.example.org.evil", "[::1"})
    EXPECT_FALSE(local.allowed(no)) << no;
  const HostCheck all("0.0.0.0", {});
  EXPECT_TRUE(all.allowed("10.1.2.3:8080"));
  EXPECT_TRUE(all.allowed("[fe80::1]:8080"));
  EXPECT_FALSE(all.allowed("rebind.evil.example:8080"));
  EXPECT_TRUE(HostCheck("127.0.0.1", {"*"}).allowed("anything.example"));
}

TEST(HttpText, TokensAndDecoding) {
  EXPECT_TRUE(net::tokens_equal("secret", "secret"));
  EXPECT_FALSE(net::tokens_equal("secret", "secreT"));
  EXPECT_FALSE(net::tokens_equal("secret", "secret2"));
  EXPECT_FALSE(net::tokens_equal("", "x"));
  EXPECT_EQ(net::url_decode("%ff%2"), "\xff%2");
  EXPECT_EQ(net::token_from("", "/ws?token=a%2Bb"), "a+b");
  net::Access open;
  EXPECT_TRUE(open.who("").admin);
  net::Access access("root-token", {{"alice", "alice-token"}});
  EXPECT_FALSE(access.who("").authorized);
  EXPECT_TRUE(access.who("root-token").admin);
  EXPECT_EQ(access.who("alice-token").name, "alice");
  EXPECT_FALSE(access.who("alice-token").admin);
}

TEST(StaticFiles, OnlyListedRegularFilesInsideTheRoot) {
  test::TempDir tmp;
  fs::create_directories(tmp / "web/src");
  write_file(tmp / "web/index.html", "<html>");
  write_file(tmp / "web/src/main.js", "//");
  write_file(tmp / "secret", "token");
  fs::create_symlink(tmp / "secret", tmp / "web/linked");
  ::mkfifo((tmp / "web/fifo").c_str(), 0600);
  net::StaticFiles files;
  files.add_root(tmp / "web", "/");
  EXPECT_TRUE(files.find("/"));
  EXPECT_TRUE(files.find("/src/main.js"));
  for (const std::string& p :
       std::vector<std::string>{"//etc/passwd", "//proc/self/cmdline", "/linked", "/fifo", "/../secret",
                                "/src/../index.html", "//dev/zero", "/" + (tmp / "secret").string()})
    EXPECT_FALSE(files.find(p)) << p;
  EXPECT_EQ(*net::StaticFiles::read(*files.find("/index.html")), "<html>");
  EXPECT_FALSE(net::StaticFiles::read("/dev/zero"));
}
