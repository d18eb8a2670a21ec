// Chunked volumes (server/chunked/): OME-Zarr written and read back at every level, regions read
// chunk by chunk, hand-made zarr and Neuroglancer precomputed folders, and each refusal.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "chunked/chunk_codec.h"
#include "chunked/chunked_volume.h"
#include "chunked/zarr_writer.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"
#include "unit/chunked_test_util.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace peakcast;
using namespace peakcast::chunked;
using test::bytes_str;
using test::refusal;
using test::write_json;

namespace {

// The stored value the writer's level k+1 voxel (x, y, z) must hold: the mean of its 2x2x2 block
// of level k, rounded half away from zero for integers.
double block_mean(const Volume& v, int64_t x, int64_t y, int64_t z) {
  double s = 0;
  int n = 0;
  const auto& d = v.dims();
  for (int64_t k = 2 * z; k < std::min(2 * z + 2, d[2]); ++k)
    for (int64_t j = 2 * y; j < std::min(2 * y + 2, d[1]); ++j)
      for (int64_t i = 2 * x; i < std::min(2 * x + 2, d[0]); ++i, ++n) s += v.stored(size_t((k * d[1] + j) * d[0] + i));
  return v.type() == VoxelType::F32 ? double(float(s / n)) : double(std::lround(s / n));
}

}  // namespace

TEST(Zarr, WrittenPyramidReadsBackAtEveryLevel) {
  test::TempDir tmp;
  for (SourceType type : {SourceType::U8, SourceType::I8, SourceType::U16, SourceType::I16, SourceType::F32}) {
    for (const char* comp : {"blosc", "zstd", "zlib", "gzip", "none"}) {
      SCOPED_TRACE(std::string(to_string(type)) + " " + comp);
      const Volume src = test::anisotropic_blobs(type, {37, 21, 19});
      const fs::path out = tmp / (std::string(to_string(type)) + comp + ".zarr");
      ZarrWriteOptions o;
      o.chunk = 8;
      o.pyramid = true;
      o.compressor = compressor_by_name(comp);
      const auto report = write_ome_zarr(src, out, o);
      EXPECT_EQ(report.levels, 4);  // 37 -> 19 -> 10 -> 5 (<= 8)
      EXPECT_FALSE(fs::exists(out.string() + ".partial-" + std::to_string(::getpid())));
      const Volume back = load_volume(out);
      EXPECT_TRUE(test::same_volume(src, back));
      const auto cv = open_chunked(out);
      ASSERT_EQ(cv->levels().size(), 4u);
      LoadOptions l1;
      l1.level = 1;
      const Volume half = load_volume(out, l1);
      ASSERT_EQ(half.dims(), (Dims{19, 11, 10}));
      EXPECT_DOUBLE_EQ(half.spacing.x, 2 * src.spacing.x);
      EXPECT_DOUBLE_EQ(half.origin.y, src.origin.y + 0.5 * src.spacing.y);  // the 2-voxel block's centre
      EXPECT_EQ(half.value_offset, src.value_offset);
      int64_t wrong = 0;
      for (int64_t z = 0; z < 10; ++z)
        for (int64_t y = 0; y < 11; ++y)
          for (int64_t x = 0; x < 19; ++x)
            wrong += half.stored(size_t((z * 11 + y) * 19 + x)) != block_mean(src, x, y, z);
      EXPECT_EQ(wrong, 0);
    }
  }
}

TEST(Zarr, RegionsReadOnlyTheirChunks) {
  test::TempDir tmp;
  const Volume src = test::anisotropic_blobs(SourceType::U16, {40, 30, 20});
  ZarrWriteOptions o;
  o.chunk = 7;
  write_ome_zarr(src, tmp / "v.zarr", o);
  // A chunk outside the region is corrupted: a region read never touches it.
  test::write_file(tmp / "v.zarr/0/2/4/5", "garbage");
  LoadOptions r;
  r.region = VoxelRegion{{3, 5, 0}, {30, 26, 13}};
  const Volume part = load_volume(tmp / "v.zarr", r);
  ASSERT_EQ(part.dims(), (Dims{27, 21, 13}));
  EXPECT_EQ(part.source_dims, src.dims());
  EXPECT_EQ(part.region_lo, (Dims{3, 5, 0}));
  EXPECT_DOUBLE_EQ(part.origin.x, src.origin.x + 3 * src.spacing.x);
  int64_t wrong = 0;
  for (int64_t z = 0; z < 13; ++z)
    for (int64_t y = 0; y < 21; ++y)
      for (int64_t x = 0; x < 27; ++x)
        wrong += part.stored(size_t((z * 21 + y) * 27 + x)) != src.stored(size_t(((z)*30 + y + 5) * 40 + x + 3));
  EXPECT_EQ(wrong, 0);
  EXPECT_NE(refusal(tmp / "v.zarr").find("0/2/4/5"), std::string::npos) << "the whole read names the bad chunk";
}

// A hand-made 5D OME-Zarr (t, c, z, y, x) with "." keys, big-endian uint16, a missing chunk.
TEST(Zarr, TimeAndChannelAxesAndMissingChunks) {
  test::TempDir tmp;
  const fs::path root = tmp / "tc.zarr";
  fs::create_directories(root / "0");
  write_json(root / ".zattrs", {{"multiscales",
                                 {{{"version", "0.4"},
                                   {"axes",
                                    {{{"name", "t"}, {"type", "time"}},
                                     {{"name", "c"}, {"type", "channel"}},
                                     {{"name", "z"}, {"type", "space"}},
                                     {{"name", "y"}, {"type", "space"}},
                                     {{"name", "x"}, {"type", "space"}}}},
                                   {"datasets",
                                    {{{"path", "0"},
                                      {"coordinateTransformations",
                                       {{{"type", "scale"}, {"scale", {1, 1, 0.5, 0.25, 0.125}}},
                                        {{"type", "translation"}, {"translation", {0, 0, 3, 2, 1}}}}}}}}}}}});
  // shape t2 c3 z4 y3 x5; chunks t1 c2 z4 y3 x3: x splits in two chunks, c in two.
  write_json(root / "0/.zarray", {{"zarr_format", 2},
                                  {"shape", {2, 3, 4, 3, 5}},
                                  {"chunks", {1, 2, 4, 3, 3}},
                                  {"dtype", ">u2"},
                                  {"compressor", nullptr},
                                  {"fill_value", 7},
                                  {"order", "C"},
                                  {"filters", nullptr}});
  auto value = [](int t, int c, int z, int y, int x) { return uint16_t(1000 * t + 100 * c + 20 * z + 5 * y + x); };
  for (int t = 0; t < 2; ++t)
    for (int cc = 0; cc < 2; ++cc)
      for (int cx = 0; cx < 2; ++cx) {
        if (t == 1 && cc == 1 && cx == 1) continue;  // missing: reads as the fill value
        std::string bytes;
        for (int c = 0; c < 2; ++c)
          for (int z = 0; z < 4; ++z)
            for (int y = 0; y < 3; ++y)
              for (int x = 0; x < 3; ++x) {
                const uint16_t v = value(t, cc * 2 + c, z, y, cx * 3 + x);
                bytes += char(v >> 8);
                bytes += char(v & 0xff);
              }
        test::write_file(root / ("0/" + std::to_string(t) + "." + std::to_string(cc) + ".0.0." + std::to_string(cx)),
                         bytes);
      }
  for (auto [t, c] : {std::pair{0, 0}, {1, 2}, {1, 1}}) {
    LoadOptions o;
    o.time_point = t;
    o.channel = c;
    const Volume v = load_volume(root, o);
    ASSERT_EQ(v.dims(), (Dims{5, 3, 4}));
    EXPECT_EQ(v.time_point, t);  // a time series: which point, of how many
    EXPECT_EQ(v.time_points, 2);
    EXPECT_DOUBLE_EQ(v.spacing.x, 0.125);
    EXPECT_DOUBLE_EQ(v.spacing.z, 0.5);
    EXPECT_DOUBLE_EQ(v.origin.x, 1.0);
    EXPECT_DOUBLE_EQ(v.origin.z, 3.0);
    int64_t wrong = 0;
    for (int z = 0; z < 4; ++z)
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x) {
          const bool missing = t == 1 && c >= 2 && x >= 3;
          wrong += v.value(x, y, z) != (missing ? 7 : value(t, c, z, y, x));
        }
    EXPECT_EQ(wrong, 0) << "t " << t << " c " << c;
  }
  LoadOptions bad;
  bad.channel = 3;
  EXPECT_NE(refusal(root, bad).find("channel 3 is outside 0..2"), std::string::npos);
  bad = {};
  bad.time_point = 2;
  EXPECT_NE(refusal(root, bad).find("time point 2 is outside 0..1"), std::string::npos);
  bad = {};
  bad.level = 1;
  EXPECT_NE(refusal(root, bad).find("level 1 does not exist"), std::string::npos);
}

TEST(Zarr, Refusals) {
  test::TempDir tmp;
  const Volume src = test::anisotropic_blobs(SourceType::U8, {9, 8, 7});
  ZarrWriteOptions o;
  o.chunk = 4;
  o.compressor = compressor_by_name("zstd");
  write_ome_zarr(src, tmp / "ok.zarr", o);
  ASSERT_EQ(refusal(tmp / "ok.zarr"), "");
  EXPECT_THROW(write_ome_zarr(src, tmp / "ok.zarr", o), VolumeError) << "an existing output is never overwritten";

  auto variant = [&](const std::string& name, const std::function<void(const fs::path&)>& change) {
    const fs::path p = tmp / name;
    fs::copy(tmp / "ok.zarr", p, fs::copy_options::recursive);
    change(p);
    return refusal(p);
  };
  auto edit_zarray = [](const fs::path& root, const std::function<void(json&)>& f) {
    std::ifstream in(root / "0/.zarray");
    json j = json::parse(in);
    f(j);
    write_json(root / "0/.zarray", j);
  };
  auto edit_zattrs = [](const fs::path& root, const std::function<void(json&)>& f) {
    std::ifstream in(root / ".zattrs");
    json j = json::parse(in);
    f(j);
    write_json(root / ".zattrs", j);
  };
  const auto cut = [](const fs::path& f) {
    const auto n = fs::file_size(f);
    fs::resize_file(f, n - 3);
  };
  EXPECT_NE(variant("trunc", [&](const fs::path& p) { cut(p / "0/1/1/1"); }).find("0/1/1/1"), std::string::npos);
  EXPECT_NE(variant("long",
                    [&](const fs::path& p) {
                      const auto full =
                          encode_chunk(compressor_by_name("zstd"), std::vector<uint8_t>(65, 1).data(), 65, 1);
                      test::write_file(p / "0/0/0/0", bytes_str(full));
                    })
                .find("more than its 64 bytes"),
            std::string::npos);
  EXPECT_NE(variant("short",
                    [&](const fs::path& p) {
                      const auto part =
                          encode_chunk(compressor_by_name("zstd"), std::vector<uint8_t>(63, 1).data(), 63, 1);
                      test::write_file(p / "0/0/0/0", bytes_str(part));
                    })
                .find("truncated chunk: 63 of 64"),
            std::string::npos);
  EXPECT_NE(variant("dtype", [&](const fs::path& p) { edit_zarray(p, [](json& j) { j["dtype"] = "<u8"; }); })
                .find("dtype '<u8' is not supported"),
            std::string::npos);
  EXPECT_NE(variant("forder", [&](const fs::path& p) { edit_zarray(p, [](json& j) { j["order"] = "F"; }); })
                .find("order must be \"C\""),
            std::string::npos);
  EXPECT_NE(variant("filters",
                    [&](const fs::path& p) {
                      edit_zarray(p, [](json& j) { j["filters"] = json::array({{{"id", "delta"}}}); });
                    })
                .find("filters are not supported"),
            std::string::npos);
  EXPECT_NE(
      variant("codec", [&](const fs::path& p) { edit_zarray(p, [](json& j) {
                                                  j["compressor"] = {{"id", "lzma"}};
                                                }); })
          .find("compressor 'lzma' is not supported"),
      std::string::npos);
  EXPECT_NE(variant("huge",
                    [&](const fs::path& p) {
                      edit_zarray(p, [](json& j) { j["chunks"] = {int64_t(1) << 40, int64_t(1) << 40, 4}; });
                    })
                .find("a chunk is larger than"),
            std::string::npos);
  EXPECT_NE(variant("v3", [&](const fs::path& p) { edit_zarray(p, [](json& j) { j["zarr_format"] = 3; }); })
                .find("zarr_format must be 2"),
            std::string::npos);
  EXPECT_NE(variant("fill", [&](const fs::path& p) { edit_zarray(p, [](json& j) { j["fill_value"] = 300; }); })
                .find("fill_value 300 is not a uint8 value"),
            std::string::npos);
  EXPECT_NE(variant("escape",
                    [&](const fs::path& p) {
                      edit_zattrs(p, [](json& j) { j["multiscales"][0]["datasets"][0]["path"] = "../ok.zarr/0"; });
                    })
                .find("must be a relative path inside"),
            std::string::npos);
  EXPECT_NE(variant("absolute",
                    [&](const fs::path& p) {
                      edit_zattrs(p, [](json& j) { j["multiscales"][0]["datasets"][0]["path"] = "/etc"; });
                    })
                .find("must be a relative path inside"),
            std::string::npos);
  EXPECT_NE(variant("axes2d",
                    [&](const fs::path& p) { edit_zattrs(p, [](json& j) { j["multiscales"][0]["axes"].erase(0); }); })
                .find("2 axes for a 3-dimensional array"),
            std::string::npos);
  EXPECT_NE(variant("xyz",
                    [&](const fs::path& p) {
                      edit_zattrs(p, [](json& j) {
                        std::swap(j["multiscales"][0]["axes"][0], j["multiscales"][0]["axes"][2]);
                      });
                    })
                .find("axes must be [t,] [c,] z, y, x"),
            std::string::npos);
  EXPECT_NE(variant("axisname",  // a name not in NGFF's list, with no type that says what it is
                    [&](const fs::path& p) {
                      edit_zattrs(p, [](json& j) { j["multiscales"][0]["axes"][0] = {{"name", "q"}}; });
                    })
                .find("axis 'q' is not a time, channel or x/y/z axis"),
            std::string::npos);
  EXPECT_NE(variant("nojson", [&](const fs::path& p) { test::write_file(p / ".zattrs", "{not json"); })
                .find("not valid JSON"),
            std::string::npos);
  EXPECT_NE(variant("jsontype", [&](const fs::path& p) { edit_zarray(p, [](json& j) { j["zarr_format"] = "2"; }); })
                .find("metadata: "),
            std::string::npos);
  EXPECT_NE(variant("tiny",
                    [&](const fs::path& p) {
                      edit_zarray(p, [](json& j) {
                        j["shape"] = {1600, 1600, 1600};
                        j["chunks"] = {1, 1, 1};
                      });
                    })
                .find("chunks this small are refused"),
            std::string::npos);
  EXPECT_NE(variant("origin",
                    [&](const fs::path& p) {
                      edit_zattrs(p, [](json& j) {
                        j["multiscales"][0]["coordinateTransformations"] = {
                            {{"type", "scale"}, {"scale", {1e308, 1e308, 1e308}}}};  // times 2: inf
                      });
                    })
                .find("finite"),
            std::string::npos);
  LoadOptions small;
  small.max_voxels = 100;
  EXPECT_NE(refusal(tmp / "ok.zarr", small).find("exceeds the limit"), std::string::npos);
}

TEST(Zarr, BareArrayWithDotKeys) {
  test::TempDir tmp;
  const fs::path root = tmp / "bare.zarr";
  fs::create_directories(root);
  write_json(root / ".zarray", {{"zarr_format", 2},
                                {"shape", {2, 2, 3}},
                                {"chunks", {2, 2, 3}},
                                {"dtype", "<f4"},
                                {"compressor", {{"id", "zlib"}, {"level", 1}}},
                                {"fill_value", "NaN"},
                                {"order", "C"},
                                {"filters", nullptr},
                                {"dimension_separator", "."}});
  std::vector<float> v(12);
  for (int i = 0; i < 12; ++i) v[size_t(i)] = 0.5f * float(i);
  const auto z = encode_chunk(compressor_by_name("zlib"), reinterpret_cast<const uint8_t*>(v.data()), 48, 4);
  test::write_file(root / "0.0.0", bytes_str(z));
  const Volume vol = load_volume(root);
  ASSERT_EQ(vol.dims(), (Dims{3, 2, 2}));
  EXPECT_DOUBLE_EQ(vol.value(2, 1, 1), 5.5);
  EXPECT_DOUBLE_EQ(vol.max_value, 5.5);
}

TEST(Zarr, MemoryBudgetPicksTheFinestLevelThatFits) {
  test::TempDir tmp;
  const Volume src = test::anisotropic_blobs(SourceType::U16, {40, 30, 20});  // 48000 bytes
  ZarrWriteOptions o;
  o.chunk = 8;
  o.pyramid = true;
  write_ome_zarr(src, tmp / "p.zarr", o);
  LoadOptions budget;
  budget.memory_budget_bytes = 48000;
  EXPECT_EQ(load_volume(tmp / "p.zarr", budget).pyramid_level, 0);
  budget.memory_budget_bytes = 47999;
  const Volume l1 = load_volume(tmp / "p.zarr", budget);
  EXPECT_EQ(l1.pyramid_level, 1);
  EXPECT_EQ(l1.dims(), (Dims{20, 15, 10}));
  EXPECT_EQ(l1.full_dims, src.dims());
  EXPECT_EQ(l1.pyramid_levels, 4);  // 40, 20, 10, 5 (<= 8)
  budget.memory_budget_bytes = 10;
  EXPECT_NE(refusal(tmp / "p.zarr", budget).find("even the coarsest level (5x4x3) exceeds"), std::string::npos);
  // Other formats are refused past the budget, before anything is allocated; regions are not.
  write_volume(tmp / "v.nrrd", src);
  budget.memory_budget_bytes = 47999;
  EXPECT_NE(refusal(tmp / "v.nrrd", budget).find("exceeds the memory budget"), std::string::npos);
  budget.region = VoxelRegion{{0, 0, 0}, {40, 30, 10}};
  EXPECT_EQ(refusal(tmp / "v.nrrd", budget), "");
}
