// The render request: the 8-bit output equals encode::to_rgb8 of the
// float output; tiles equal the same pixels of a full render; stats as one JSON form.
#include <cmath>
#include <fstream>
#include <set>

#include "encode/png.h"
#include "gpu/gpu_fixture.h"

using namespace peakcast;
using nlohmann::json;

namespace {

json tf_over_range(const Volume& v, std::vector<std::array<double, 5>> pts) {
  json out = json::array();
  for (auto& p : pts) out.push_back({v.min_value + p[0] * (v.max_value - v.min_value), p[1], p[2], p[3], p[4]});
  return {{"points", out}};
}

std::shared_ptr<Volume> blobs() {
  static auto v = test::make_volume(GeneratorKind::Blobs, {48, 40, 36}, SourceType::U8, {1.0, 1.25, 1.5});
  return v;
}

// Scenes that reach every variant the stream uses: post/peaks/preint, tricubic, shading (its
// specular term goes above 1 and gets clamped), orthographic, a coloured background.
// 97x61 pixels: not a multiple of the compute path's 8x8 groups.
std::vector<std::pair<std::string, json>> scenes(const Volume& v) {
  const json tf = tf_over_range(v, {{0.0, 0, 0, 0, 0},
                                    {0.25, 0.1, 0.3, 1.0, 0.0},
                                    {0.5, 1.0, 0.7, 0.2, 0.5},
                                    {0.7, 1.0, 1.0, 1.0, 0.0},
                                    {1.0, 1, 1, 1, 0.9}});
  const json img = {{"width", 97}, {"height", 61}};
  return {
      {"post", {{"tf", tf}, {"image", img}, {"background", {0.1, 0.2, 0.3}}}},
      {"tricubic_shaded", {{"tf", tf}, {"image", img}, {"render", {{"filter", "tricubic"}, {"shading", true}}}}},
      {"peaks", {{"tf", tf}, {"image", img}, {"render", {{"classification", "peaks"}, {"shading", true}}}}},
      {"preint", {{"tf", tf}, {"image", img}, {"render", {{"classification", "preint"}}}}},
      {"ortho",
       {{"tf", tf},
        {"image", img},
        {"camera",
         {{"eye", {80, -20, 70}},
          {"center", {23.5, 24.375, 26.25}},
          {"up", {0, 0, 1}},
          {"projection", "orthographic"},
          {"height", 60}}}}},
  };
}

const char* name(render::RenderPath p) { return p == render::RenderPath::Compute ? "comp" : "frag"; }

render::RenderResult draw(const render::ResidentVolume& gv, const ResolvedScene& s, render::RenderPath path,
                          render::RenderOutput out, std::optional<render::PixelRect> tile = std::nullopt,
                          render::RenderStats* st = nullptr, bool sample_stats = false) {
  render::RenderRequest r;
  r.path = path;
  r.output = out;
  r.tile = tile;
  r.sample_stats = sample_stats;
  return test::gpu().caster->render(gv, s, r, st);
}

}  // namespace

// Measured on llvmpipe: identical (0 bytes differ) for every scene and path.
TEST(Rgb8Output, EqualsToRgb8OfTheFloatOutput) {
  auto v = blobs();
  test::TestVolume gv(v);
  for (const auto& [label, over] : scenes(*v))
    for (auto path : {render::RenderPath::Fragment, render::RenderPath::Compute}) {
      const ResolvedScene s = test::make_scene(*v, over);
      const Image f = draw(gv, s, path, render::RenderOutput::Float).image;
      const render::Rgb8Image b = draw(gv, s, path, render::RenderOutput::Rgb8).rgb8;
      const std::vector<unsigned char> want = encode::to_rgb8(f);
      ASSERT_EQ(b.width, f.width);
      ASSERT_EQ(b.height, f.height);
      ASSERT_EQ(b.rgb.size(), want.size());
      size_t differ = 0, off_by_more = 0, nonzero = 0;
      for (size_t k = 0; k < want.size(); ++k) {
        differ += b.rgb[k] != want[k];
        off_by_more += std::abs(int(b.rgb[k]) - int(want[k])) > 1;
        nonzero += want[k] != 0;
      }
      std::printf("%-16s %s: %zu of %zu bytes differ (%zu by more than 1/255)\n", label.c_str(), name(path), differ,
                  want.size(), off_by_more);
      EXPECT_GT(nonzero, want.size() / 10) << label << ": the scene should show something";
      EXPECT_EQ(differ, 0u) << label << " " << name(path);
    }
}

// The tile's pixels equal the same pixels of the full render exactly, for both outputs and both
// paths; assembling the tiles gives the full image.
TEST(Tiles, EqualTheFullRenderExactly) {
  auto v = blobs();
  test::TestVolume gv(v);
  const auto all = scenes(*v);
  for (const auto& [label, over] : {all[1], all[2], all[4]}) {
    const ResolvedScene s = test::make_scene(*v, over);
    const int W = s.scene.width, H = s.scene.height;
    // Layouts: a regular grid with edge tiles, tiles of odd sizes, one row, one column.
    std::vector<std::vector<render::PixelRect>> layouts = {
        render::tile_grid(W, H, 32, 32), render::tile_grid(W, H, 13, 7), render::tile_grid(W, H, W, 1),
        render::tile_grid(W, H, 1, H)};
    for (auto path : {render::RenderPath::Fragment, render::RenderPath::Compute}) {
      render::RenderStats full_st;
      const Image full = draw(gv, s, path, render::RenderOutput::Float, std::nullopt, &full_st).image;
      const render::Rgb8Image full8 = draw(gv, s, path, render::RenderOutput::Rgb8).rgb8;
      for (size_t li = 0; li < layouts.size(); ++li) {
        Image asm_f(W, H);
        render::Rgb8Image asm_8(W, H);
        render::RenderStats total;
        for (size_t k = 0; k < layouts[li].size(); ++k) {
          const auto& r = layouts[li][k];
          render::RenderStats st;
          render::place_tile(asm_f, r, draw(gv, s, path, render::RenderOutput::Float, r, &st).image);
          render::place_tile(asm_8, r, draw(gv, s, path, render::RenderOutput::Rgb8, r).rgb8);
          if (k == 0)
            total = st;
          else
            total.merge(st);
        }
        SCOPED_TRACE(label + " " + name(path) + " layout " + std::to_string(li));
        EXPECT_EQ(asm_f.rgba, full.rgba);
        EXPECT_EQ(asm_f.samples, full.samples);
        EXPECT_EQ(asm_8.rgb, full8.rgb);
        EXPECT_EQ(total.tiles, int(layouts[li].size()));
        EXPECT_EQ(total.rays_hit, full_st.rays_hit);
        EXPECT_EQ(total.samples_total, full_st.samples_total);
        EXPECT_EQ(total.samples_max, full_st.samples_max);
      }
      // Single tiles: 1x1 at each corner and the middle, a tile at the bottom-right edge.
      for (render::PixelRect r : {render::PixelRect{0, 0, 1, 1}, render::PixelRect{W - 1, 0, 1, 1},
                                  render::PixelRect{0, H - 1, 1, 1}, render::PixelRect{W - 1, H - 1, 1, 1},
                                  render::PixelRect{W / 2, H / 2, 1, 1}, render::PixelRect{W - 9, H - 5, 9, 5}}) {
        const Image t = draw(gv, s, path, render::RenderOutput::Float, r).image;
        const render::Rgb8Image t8 = draw(gv, s, path, render::RenderOutput::Rgb8, r).rgb8;
        for (int y = 0; y < r.h; ++y)
          for (int x = 0; x < r.w; ++x) {
            for (int c = 0; c < 4; ++c)
              ASSERT_EQ(t.pixel(x, y)[c], full.pixel(r.x + x, r.y + y)[c]) << r.to_string() << " " << name(path);
            for (int c = 0; c < 3; ++c)
              ASSERT_EQ(t8.rgb[(size_t(y) * r.w + x) * 3 + c], full8.rgb[(size_t(r.y + y) * W + r.x + x) * 3 + c])
                  << r.to_string() << " " << name(path);
          }
      }
    }
  }
}

// A still's tiles between another session's frames (another TF, another classification) reuse
// the tables and occupancy both built at their first draw: nothing is rebuilt per tile.
TEST(Tiles, InterleavedWithAnotherTfRebuildNothing) {
  auto v = blobs();
  test::TestVolume gv(v);
  const auto all = scenes(*v);
  for (auto [a, b] : {std::pair{all[3].second, all[2].second}, std::pair{all[0].second, all[3].second}}) {
    json other_tf = tf_over_range(*v, {{0.0, 0, 0, 0, 0}, {0.4, 0.2, 0.5, 1.0, 0.3}, {1.0, 1, 1, 1, 0.8}});
    b["tf"] = other_tf;
    const ResolvedScene still = test::make_scene(*v, a), view = test::make_scene(*v, b);
    draw(gv, still, render::RenderPath::Fragment, render::RenderOutput::Rgb8, render::PixelRect{0, 0, 8, 8});
    draw(gv, view, render::RenderPath::Fragment, render::RenderOutput::Rgb8);
    const size_t built = test::gpu().switches->table_builds();
    for (const auto& r : render::tile_grid(still.scene.width, still.scene.height, 32, 32)) {
      draw(gv, still, render::RenderPath::Fragment, render::RenderOutput::Rgb8, r);
      draw(gv, view, render::RenderPath::Fragment, render::RenderOutput::Rgb8);
    }
    EXPECT_EQ(test::gpu().switches->table_builds(), built);
  }
}

TEST(Tiles, RefusesRectanglesOutsideTheImage) {
  auto v = blobs();
  test::TestVolume gv(v);
  const ResolvedScene s = test::make_scene(*v, {{"image", {{"width", 40}, {"height", 30}}}});
  for (render::PixelRect r :
       {render::PixelRect{0, 0, 0, 5}, render::PixelRect{0, 0, 5, 0}, render::PixelRect{-1, 0, 5, 5},
        render::PixelRect{0, -1, 5, 5}, render::PixelRect{36, 0, 5, 5}, render::PixelRect{0, 26, 5, 5},
        render::PixelRect{1, 1, 2147483647, 1}}) {
    try {
      draw(gv, s, render::RenderPath::Fragment, render::RenderOutput::Rgb8, r);
      ADD_FAILURE() << r.to_string() << " was accepted";
    } catch (const std::invalid_argument& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("tile " + r.to_string()), std::string::npos) << msg;
      EXPECT_TRUE(msg.find("40x30") != std::string::npos || msg.find("at least 1 pixel") != std::string::npos) << msg;
    }
  }
  EXPECT_THROW(render::tile_grid(40, 30, 0, 8), std::invalid_argument);
  EXPECT_THROW(render::tile_grid(0, 30, 8, 8), std::invalid_argument);
  Image full(40, 30), tile(8, 8);
  EXPECT_THROW(render::place_tile(full, {0, 0, 8, 7}, tile), std::invalid_argument);   // size differs
  EXPECT_THROW(render::place_tile(full, {36, 0, 8, 8}, tile), std::invalid_argument);  // outside
}

// Rgb8 reads the sample counts only when asked; then they equal the float path's.
TEST(Rgb8Output, SampleStatsOnlyWhenAsked) {
  auto v = blobs();
  test::TestVolume gv(v);
  const ResolvedScene s = test::make_scene(*v, scenes(*v)[0].second);
  render::RenderStats f, without, with;
  draw(gv, s, render::RenderPath::Fragment, render::RenderOutput::Float, std::nullopt, &f);
  draw(gv, s, render::RenderPath::Fragment, render::RenderOutput::Rgb8, std::nullopt, &without);
  draw(gv, s, render::RenderPath::Fragment, render::RenderOutput::Rgb8, std::nullopt, &with, true);
  EXPECT_TRUE(f.has_samples);
  EXPECT_FALSE(without.has_samples);
  EXPECT_EQ(without.rays_hit, 0);
  EXPECT_FALSE(without.to_json().contains("samples_per_ray"));
  EXPECT_TRUE(with.has_samples);
  EXPECT_GT(f.rays_hit, 0);
  EXPECT_EQ(with.rays_hit, f.rays_hit);
  EXPECT_EQ(with.samples_total, f.samples_total);
  EXPECT_EQ(with.samples_max, f.samples_max);
  EXPECT_NE(with.variant.find("+rgb8"), std::string::npos) << with.variant;
}

// One JSON form: the stream's key names (proto/server_messages.schema.json $defs/stats), and a
// to_string showing the same keys and values.
TEST(RenderStats, JsonUsesTheStreamKeysAndToStringMatches) {
  auto v = blobs();
  test::TestVolume gv(v);
  const ResolvedScene s = test::make_scene(*v, scenes(*v)[2].second);  // peaks: peaks and empty cells > 0
  render::RenderStats st;
  draw(gv, s, render::RenderPath::Fragment, render::RenderOutput::Float, std::nullopt, &st);
  const json j = st.to_json();
  std::set<std::string> want = {
      "render_ms",          "readback_ms", "table_ms", "samples_per_ray", "samples_per_ray_max", "rays_hit",
      "rays_at_sample_cap", "sample_cap",  "variant",  "peaks",           "empty_macrocells",    "tiles",
      "tf_source",          "warnings"};
  std::set<std::string> got;
  for (auto& [k, _] : j.items()) got.insert(k);
  want.insert("compile_ms");
  if (!test::cpu_backend()) want.insert("gpu_ms");  // a timer query: the GPU's own time
  EXPECT_EQ(got, want);
  EXPECT_EQ(j["samples_per_ray"].get<double>(), st.samples_mean);
  EXPECT_EQ(j["variant"].get<std::string>(), st.variant);
  EXPECT_GT(j["peaks"].get<int>(), 0);
  // Every key is declared in the stream's stats message with a matching type (the schema has
  // additionalProperties: false, so a key missing there breaks the net tests' validation).
  const json schema =
      json::parse(std::ifstream(std::string(PEAKCAST_SOURCE_DIR) + "/proto/server_messages.schema.json"));
  const json& props = schema["$defs"]["stats"]["properties"];
  for (auto& [k, val] : j.items()) {
    ASSERT_TRUE(props.contains(k)) << k << " is not in $defs/stats";
    const std::string type = props[k]["type"];
    const bool ok = type == "string"    ? val.is_string()
                    : type == "array"   ? val.is_array()
                    : type == "integer" ? val.is_number_integer()
                                        : val.is_number();
    EXPECT_TRUE(ok) << k << ": schema says " << type << ", to_json gives " << val.dump();
  }
  const std::string text = st.to_string();
  for (auto& [k, val] : j.items()) {
    const std::string shown = k + "=" + (val.is_string() ? val.get<std::string>() : val.dump());
    EXPECT_NE(text.find(shown), std::string::npos) << shown << " not in " << text;
  }
}
