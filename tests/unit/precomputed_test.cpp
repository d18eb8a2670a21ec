// Neuroglancer precomputed folders made here (raw, gzip and .gz chunks, channels, a missing
// chunk), their refusals, and the chunk codecs against corrupt streams.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "chunked/chunk_codec.h"
#include "core/volume_io.h"
#include "unit/chunked_test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace peakcast;
using namespace peakcast::chunked;
using test::bytes_str;
using test::refusal;
using test::write_json;

namespace {

// A precomputed image: 10x7x5 uint16, 2 channels, chunks 4x4x4, voxel_offset (100, 0, 50).
fs::path make_precomputed(const fs::path& root, bool gzip_files) {
  fs::create_directories(root / "1_1_2");
  write_json(root / "info", {{"type", "image"},
                             {"data_type", "uint16"},
                             {"num_channels", 2},
                             {"scales",
                              {{{"key", "1_1_2"},
                                {"size", {10, 7, 5}},
                                {"resolution", {1, 1, 2}},
                                {"voxel_offset", {100, 0, 50}},
                                {"chunk_sizes", {{4, 4, 4}}},
                                {"encoding", "raw"}}}}});
  for (int cz = 0; cz < 2; ++cz)
    for (int cy = 0; cy < 2; ++cy)
      for (int cx = 0; cx < 3; ++cx) {
        if (cx == 2 && cy == 1 && cz == 1) continue;  // missing: 0
        const int x0 = cx * 4, x1 = std::min(x0 + 4, 10), y0 = cy * 4, y1 = std::min(y0 + 4, 7), z0 = cz * 4,
                  z1 = std::min(z0 + 4, 5);
        std::vector<uint16_t> d;
        for (int c = 0; c < 2; ++c)
          for (int z = z0; z < z1; ++z)
            for (int y = y0; y < y1; ++y)
              for (int x = x0; x < x1; ++x) d.push_back(uint16_t(1000 * c + 100 * z + 10 * y + x));
        const std::string name = std::to_string(100 + x0) + "-" + std::to_string(100 + x1) + "_" + std::to_string(y0) +
                                 "-" + std::to_string(y1) + "_" + std::to_string(50 + z0) + "-" +
                                 std::to_string(50 + z1);
        const auto* b = reinterpret_cast<const uint8_t*>(d.data());
        const bool gz = gzip_files && (cx + cy + cz) % 2 == 0;
        const auto bytes = gz ? encode_chunk(compressor_by_name("gzip"), b, d.size() * 2, 2)
                              : std::vector<uint8_t>(b, b + d.size() * 2);
        test::write_file(root / "1_1_2" / (name + (gz && cx == 0 ? ".gz" : "")), bytes_str(bytes));
      }
  return root;
}

}  // namespace

TEST(Precomputed, RawAndGzipChunksAndChannels) {
  test::TempDir tmp;
  for (bool gz : {false, true}) {
    const fs::path root = make_precomputed(tmp / (gz ? "gz" : "raw"), gz);
    for (int c : {0, 1}) {
      LoadOptions o;
      o.channel = c;
      const Volume v = load_volume(root, o);
      ASSERT_EQ(v.dims(), (Dims{10, 7, 5}));
      EXPECT_DOUBLE_EQ(v.spacing.z, 2.0);
      EXPECT_EQ(v.unit, "nm");              // the format's resolution is in nanometres
      EXPECT_DOUBLE_EQ(v.origin.x, 100.5);  // voxel 100 spans [100, 101) nm: its centre
      EXPECT_DOUBLE_EQ(v.origin.z, 101.0);
      int64_t wrong = 0;
      for (int z = 0; z < 5; ++z)
        for (int y = 0; y < 7; ++y)
          for (int x = 0; x < 10; ++x) {
            const bool missing = x >= 8 && y >= 4 && z >= 4;
            wrong += v.value(x, y, z) != (missing ? 0 : 1000 * c + 100 * z + 10 * y + x);
          }
      EXPECT_EQ(wrong, 0) << (gz ? "gzip" : "raw") << " channel " << c;
    }
  }
}

TEST(Precomputed, Refusals) {
  test::TempDir tmp;
  auto with_info = [&](const std::string& name, const std::function<void(json&)>& change) {
    const fs::path root = make_precomputed(tmp / name, false);
    std::ifstream in(root / "info");
    json j = json::parse(in);
    change(j);
    write_json(root / "info", j);
    return refusal(root);
  };
  EXPECT_NE(with_info("seg", [](json& j) { j["type"] = "segmentation"; }).find("is not an image"), std::string::npos);
  EXPECT_NE(with_info("u64", [](json& j) { j["data_type"] = "uint64"; }).find("data_type 'uint64' is not supported"),
            std::string::npos);
  EXPECT_NE(
      with_info("jpeg", [](json& j) { j["scales"][0]["encoding"] = "jpeg"; }).find("encoding 'jpeg' is not supported"),
      std::string::npos);
  EXPECT_NE(with_info("shard",
                      [](json& j) {
                        j["scales"][0]["sharding"] = {{"@type", "neuroglancer_uint64_sharded_v1"}};
                      })
                .find("sharded scales are not supported"),
            std::string::npos);
  EXPECT_NE(with_info("key", [](json& j) { j["scales"][0]["key"] = "../x"; }).find("relative path inside"),
            std::string::npos);
  EXPECT_NE(with_info("size",
                      [](json& j) {
                        j["scales"][0]["size"] = {10, 7};
                      })
                .find("size must be 3 numbers"),
            std::string::npos);
  EXPECT_NE(with_info("frac",
                      [](json& j) {
                        j["scales"][0]["chunk_sizes"] = {{4.5, 4, 4}};
                      })
                .find("whole numbers"),
            std::string::npos);
  EXPECT_NE(with_info("res",
                      [](json& j) {
                        j["scales"][0]["resolution"] = {1, 0, 1};
                      })
                .find("resolution must be finite"),
            std::string::npos);
  const fs::path root = make_precomputed(tmp / "trunc", false);
  fs::resize_file(root / "1_1_2/100-104_0-4_50-54", 100);
  EXPECT_NE(refusal(root).find("truncated chunk: 100 of 256 bytes"), std::string::npos);
  LoadOptions o;
  o.channel = 2;
  EXPECT_NE(refusal(make_precomputed(tmp / "chan", false), o).find("channel 2 is outside 0..1"), std::string::npos);
}

TEST(ChunkCodec, CorruptStreamsAreRefused) {
  std::vector<uint8_t> data(1000);
  for (size_t i = 0; i < data.size(); ++i) data[i] = uint8_t(i * 7);
  for (const char* name : {"zlib", "gzip", "zstd", "blosc"}) {
    SCOPED_TRACE(name);
    const auto spec = compressor_by_name(name);
    auto packed = encode_chunk(spec, data.data(), data.size(), 1);
    EXPECT_EQ(decode_chunk(spec, packed, data.size(), "c"), data);
    EXPECT_THROW(decode_chunk(spec, packed, data.size() + 1, "c"), VolumeError);
    EXPECT_THROW(decode_chunk(spec, packed, data.size() - 1, "c"), VolumeError);
    auto cut = packed;
    cut.resize(cut.size() / 2);
    EXPECT_THROW(decode_chunk(spec, cut, data.size(), "c"), VolumeError);
    auto flipped = packed;
    for (size_t i = 0; i < flipped.size(); i += 3) flipped[i] ^= 0x5a;
    try {  // refused, or (blosc without a checksum) decoded to some other bytes: never a crash
      decode_chunk(spec, flipped, data.size(), "c");
    } catch (const VolumeError&) {
    }
  }
}
