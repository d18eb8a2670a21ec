// Ray textures (Raspe & Müller 2008): the texture model, its strokes and their refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/generators.h"
#include "core/ray_texture.h"
#include "core/scene.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

json stroke(const char* channel, double u, double v, double radius, double value, const char* mode = "set",
            double falloff = 0.0, int level = 0) {
  return {{"channel", channel}, {"center", {u, v}},   {"radius", radius}, {"value", value},
          {"mode", mode},       {"falloff", falloff}, {"level", level}};
}

TEST(ray_texture, NoStrokesIsTheIdentity) {
  const RayTexture t = build_ray_texture(parse_ray_texture({{"mapping", "view"}, {"size", {64, 32}}}), 0.97);
  EXPECT_TRUE(t.is_identity());
  EXPECT_EQ(t.texels().size(), size_t(64 * 32 * 3));
  const auto v = t.at(10, 10);
  EXPECT_EQ(v[0], 1.0f);
  EXPECT_EQ(v[1], 0.97f);
  EXPECT_EQ(v[2], 0.0f);
}

TEST(ray_texture, ASetStrokeChangesItsDiskOnly) {
  RayTexture t(100, 100, 1.0);
  const TexelRect r = t.apply(parse_stroke(stroke("step", 0.5, 0.5, 0.2, 0.25), "s"));
  EXPECT_FALSE(r.empty());
  int inside = 0;
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) {
      const double d = std::hypot(x + 0.5 - 50.0, y + 0.5 - 50.0) / 100.0;
      const float s = t.at(x, y)[0];
      if (d < 0.19) {
        EXPECT_EQ(s, 0.25f) << x << "," << y;
        ++inside;
      }
      if (d > 0.21) {
        EXPECT_EQ(s, 1.0f) << x << "," << y;
      }
      if (s != 1.0f) {  // inside the returned dirty region
        EXPECT_GE(x, r.x0);
        EXPECT_LT(x, r.x1);
        EXPECT_GE(y, r.y0);
        EXPECT_LT(y, r.y1);
      }
      EXPECT_EQ(t.at(x, y)[1], 1.0f);  // other channels untouched
      EXPECT_EQ(t.at(x, y)[2], 0.0f);
    }
  EXPECT_GT(inside, 1000);
  EXPECT_LE(r.x1 - r.x0, 42);  // the region is the disk's bounding box, not the texture
}

TEST(ray_texture, ModesFalloffAndClamping) {
  RayTexture t(64, 64, 0.9);
  t.apply(parse_stroke(stroke("step", 0.5, 0.5, 1.0, 2.0, "multiply"), "s"));
  EXPECT_FLOAT_EQ(t.at(32, 32)[0], 2.0f);
  t.apply(parse_stroke(stroke("step", 0.5, 0.5, 1.0, 64.0, "multiply"), "s"));
  EXPECT_FLOAT_EQ(t.at(32, 32)[0], 8.0f);  // clamped to the channel's range
  t.apply(parse_stroke(stroke("blend", 0.5, 0.5, 1.0, -0.5, "add"), "s"));
  EXPECT_FLOAT_EQ(t.at(32, 32)[2], -0.5f);
  t.apply(parse_stroke(stroke("termination", 0.5, 0.5, 0.5, 0.5, "set", 1.0), "s"));
  const float centre = t.at(32, 32)[1], halfway = t.at(32 + 16, 32)[1], edge = t.at(32 + 31, 32)[1];
  EXPECT_NEAR(centre, 0.5f, 0.01f);  // full weight at the centre, falling off smoothly
  EXPECT_GT(halfway, centre);
  EXPECT_LT(halfway, 0.9f);
  EXPECT_NEAR(edge, 0.9f, 1e-3f);        // at 0.98 of the radius
  EXPECT_FLOAT_EQ(t.at(0, 0)[1], 0.9f);  // outside the disk
}

// Raspe §3.2: a stroke at level L changes whole 2^L x 2^L blocks (one weight per block).
TEST(ray_texture, HierarchicalStrokesEditSquareBlocks) {
  RayTexture t(64, 64, 1.0);
  const TexelRect r = t.apply(parse_stroke(stroke("step", 0.3, 0.6, 0.1, 4.0, "set", 0.0, 3), "s"));
  EXPECT_EQ(r.x0 % 8, 0);
  EXPECT_EQ(r.y0 % 8, 0);
  EXPECT_EQ(r.x1 % 8, 0);
  EXPECT_EQ(r.y1 % 8, 0);
  for (int by = 0; by < 8; ++by)
    for (int bx = 0; bx < 8; ++bx) {
      const float first = t.at(bx * 8, by * 8)[0];
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) ASSERT_EQ(t.at(bx * 8 + x, by * 8 + y)[0], first);
    }
  EXPECT_EQ(t.at(int(0.3 * 64), int(0.6 * 64))[0], 4.0f);
  EXPECT_EQ(t.at(0, 0)[0], 1.0f);
}

TEST(ray_texture, SpecRoundTripsThroughJson) {
  const json j = {
      {"mapping", "volume"},
      {"size", {32, 16}},
      {"strokes", {stroke("step", 0.1, 0.2, 0.3, 0.5), stroke("blend", 0.4, 0.5, 0.6, 0.5, "add", 0.5, 2)}}};
  const RayTextureSpec s = parse_ray_texture(j);
  EXPECT_EQ(s.mapping, RayTextureMapping::Volume);
  EXPECT_EQ(to_json(parse_ray_texture(to_json(s))), to_json(s));
  const RayTextureSpec p = parse_ray_texture({{"mapping", "view"}, {"png", "paint.png"}});
  EXPECT_EQ(p.png, "paint.png");
}

void expect_refused(const json& j, const std::string& key) {
  try {
    parse_ray_texture(j);
    ADD_FAILURE() << "accepted " << j.dump();
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}

TEST(ray_texture, BadSpecsAndStrokesAreRefusedNamingTheKey) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const json ok = {{"mapping", "view"}, {"size", {8, 8}}};
  auto with = [&](json s) {
    json j = ok;
    j["strokes"] = {s};
    return j;
  };
  expect_refused({{"size", {8, 8}}}, "render.ray_texture.mapping");
  expect_refused({{"mapping", "screen"}, {"size", {8, 8}}}, "render.ray_texture.mapping");
  expect_refused({{"mapping", "view"}}, "render.ray_texture.size");
  expect_refused({{"mapping", "view"}, {"size", {0, 8}}}, "render.ray_texture.size[0]");
  expect_refused({{"mapping", "view"}, {"size", {kMaxRayTextureSide + 1, 8}}}, "render.ray_texture.size[0]");
  expect_refused({{"mapping", "view"}, {"size", {8, 8}}, {"png", "a.png"}}, "not both");
  expect_refused({{"mapping", "view"}, {"size", {8, 8}}, {"brush", 1}}, "render.ray_texture.brush");
  expect_refused(with(stroke("step", nan, 0.5, 0.1, 1.0)), "strokes[0].center[0]");
  expect_refused(with(stroke("step", 0.5, 1.5, 0.1, 1.0)), "strokes[0].center");
  expect_refused(with(stroke("step", 0.5, 0.5, 0.0, 1.0)), "strokes[0].radius");
  expect_refused(with(stroke("step", 0.5, 0.5, 1.5, 1.0)), "strokes[0].radius");
  expect_refused(with(stroke("opacity", 0.5, 0.5, 0.1, 1.0)), "strokes[0].channel");
  expect_refused(with(stroke("step", 0.5, 0.5, 0.1, 9.0)), "strokes[0].value");
  expect_refused(with(stroke("step", 0.5, 0.5, 0.1, 0.0, "multiply")), "strokes[0].value");
  expect_refused(with(stroke("termination", 0.5, 0.5, 0.1, 1.5)), "strokes[0].value");
  expect_refused(with(stroke("blend", 0.5, 0.5, 0.1, 0.5, "paint")), "strokes[0].mode");
  expect_refused(with(stroke("blend", 0.5, 0.5, 0.1, 0.5, "set", 2.0)), "strokes[0].falloff");
  expect_refused(with(stroke("blend", 0.5, 0.5, 0.1, 0.5, "set", 0.0, kMaxStrokeLevel + 1)), "strokes[0].level");
  json many = ok;
  many["strokes"] = json::array();
  for (size_t i = 0; i <= kMaxRayTextureStrokes; ++i) many["strokes"].push_back(stroke("step", 0.5, 0.5, 0.1, 1.0));
  expect_refused(many, "render.ray_texture.strokes");
}

// A scene naming a PNG that no loader read (a path that skipped load_ray_texture_png) is
// refused when resolved, naming the key, never rendered with made-up texels.
TEST(ray_texture, AnUnreadPngIsRefusedWhenResolved) {
  GeneratorSpec g;
  g.kind = GeneratorKind::Ramp;
  g.dims = {4, 4, 4};
  const Volume v = generate_volume(g);
  const Scene s =
      parse_scene({{"volume", "v"}, {"render", {{"ray_texture", {{"mapping", "view"}, {"png", "paint.png"}}}}}});
  try {
    resolve_scene(s, v);
    ADD_FAILURE() << "a png ray texture was accepted unread";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("render.ray_texture.png"), std::string::npos) << e.what();
  }
}

// Painted strokes keep the lineage (the renderer applies only the new ones); a parse starts a
// new one; the stroke cap holds for painted strokes too.
TEST(ray_texture, PaintedStrokesKeepTheLineage) {
  const RayTextureSpec a = parse_ray_texture({{"mapping", "view"}, {"size", {8, 8}}});
  const RayTextureSpec b = parse_ray_texture({{"mapping", "view"}, {"size", {8, 8}}});
  EXPECT_NE(a.lineage, b.lineage);
  const auto a1 = with_stroke(a, parse_stroke(stroke("step", 0.5, 0.5, 0.2, 2.0), "s"));
  EXPECT_EQ(a1->lineage, a.lineage);
  EXPECT_EQ(a1->strokes.size(), 1u);
  EXPECT_EQ(a.strokes.size(), 0u);  // the old spec is unchanged (frames in flight still read it)
  RayTextureSpec full = a;
  full.strokes.assign(kMaxRayTextureStrokes, a1->strokes[0]);
  try {
    with_stroke(full, a1->strokes[0]);
    ADD_FAILURE() << "a stroke beyond the cap was taken";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("strokes already"), std::string::npos) << e.what();
  }
}

// What the strokes may cost the render thread is bounded: the sum of their bounding boxes.
TEST(ray_texture, StrokeWorkIsBounded) {
  const json big = stroke("step", 0.5, 0.5, 1.0, 2.0);  // covers a 2048^2 texture: 4.2M texels
  json spec = {{"mapping", "view"}, {"size", {2048, 2048}}, {"strokes", json::array()}};
  for (int i = 0; i < 64; ++i) spec["strokes"].push_back(big);
  const RayTextureSpec ok = parse_ray_texture(spec);  // 64 x 4.2M = 2^28: the limit itself
  EXPECT_EQ(ok.work, kMaxRayTextureWork);
  try {
    with_stroke(ok, parse_stroke(stroke("step", 0.5, 0.5, 0.01, 2.0), "s"));
    ADD_FAILURE() << "a stroke past the work limit was taken";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("texels in all"), std::string::npos) << e.what();
  }
  spec["strokes"].push_back(big);
  expect_refused(spec, "render.ray_texture.strokes");
  // A small stroke on a small texture costs its disk's box only.
  EXPECT_LE(stroke_texels(parse_stroke(stroke("step", 0.5, 0.5, 0.05, 2.0), "s"), 256, 256), 28u * 28u);
}

}  // namespace
}  // namespace peakcast
