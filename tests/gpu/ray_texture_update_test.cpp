// Ray-texture updates on the GL ray caster (Raspe §3.2): painted strokes are applied to the
// held texture and only their dirty rectangle is uploaded, with the same image as a texture
// built from scratch; PNG textures render like the strokes they were painted from.
#include <cmath>
#include <filesystem>

#include "core/ray_texture_png.h"
#include "gpu/ray_texture_scenes.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

std::shared_ptr<Volume> ml() { return test::ray_texture_volume(); }

const json& kTf = test::kRayTextureTf;

ResolvedScene scene_of(const Volume& v, std::shared_ptr<const RayTextureSpec> spec) {
  ResolvedScene s = test::make_scene(
      v, {{"image", {{"width", 96}, {"height", 96}}},
          {"camera", {{"eye", {60, 50, 100}}, {"center", {20, 20, 20}}, {"up", {0, 1, 0}}, {"fov_y", 30}}},
          {"tf", kTf},
          {"render", {{"step", 2.0}}}});
  s.scene.render.ray_texture = spec;
  s.ray_texture = spec;
  return s;
}

Stroke stroke(const char* channel, double u, double v, double radius, double value, int level = 0) {
  return parse_stroke(
      {{"channel", channel}, {"center", {u, v}}, {"radius", radius}, {"value", value}, {"level", level}}, "stroke");
}

size_t differing(const Image& a, const Image& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) n += a.rgba[i] != b.rgba[i];
  return n;
}

TEST(ray_texture, PaintedStrokesUploadOnlyTheirRegionAndMatchAFreshBuild) {
  auto v = ml();
  test::TestVolume gv(v);
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {128, 128}}}));
  spec = with_stroke(*spec, stroke("step", 0.3, 0.3, 0.2, 0.5));
  render::RenderStats st;
  test::render_gpu(gv, scene_of(*v, spec), render::RenderPath::Fragment, &st);
  EXPECT_EQ(st.ray_texture_strokes, 1);
  EXPECT_EQ(st.ray_texture_texels, 128 * 128);  // a new lineage: built and uploaded whole
  test::render_gpu(gv, scene_of(*v, spec), render::RenderPath::Fragment, &st);
  EXPECT_EQ(st.ray_texture_strokes, 0);
  EXPECT_EQ(st.ray_texture_texels, 0);  // unchanged: nothing goes up

  // A direct stroke: its disk's bounding box (radius 0.1 of 128 texels: about 26 x 26).
  spec = with_stroke(*spec, stroke("termination", 0.6, 0.5, 0.1, 0.05));
  const Image direct = test::render_gpu(gv, scene_of(*v, spec), render::RenderPath::Fragment, &st);
  std::printf("direct stroke: %lld texels uploaded, %.3f ms\n", (long long)st.ray_texture_texels, st.ray_texture_ms);
  EXPECT_EQ(st.ray_texture_strokes, 1);
  EXPECT_GT(st.ray_texture_texels, 20 * 20);
  EXPECT_LE(st.ray_texture_texels, 28 * 28);
  // A hierarchical one (level 3): whole 8 x 8 blocks.
  spec = with_stroke(*spec, stroke("blend", 0.4, 0.7, 0.12, 0.8, 3));
  const Image both = test::render_gpu(gv, scene_of(*v, spec), render::RenderPath::Fragment, &st);
  std::printf("level-3 stroke: %lld texels uploaded\n", (long long)st.ray_texture_texels);
  EXPECT_EQ(st.ray_texture_texels % 64, 0);
  EXPECT_LE(st.ray_texture_texels, 40 * 40);
  EXPECT_GT(differing(direct, both), 0u);

  // The same strokes parsed anew (a new lineage, built from scratch): the same image.
  const auto fresh = std::make_shared<const RayTextureSpec>(parse_ray_texture(to_json(*spec)));
  const Image rebuilt = test::render_gpu(gv, scene_of(*v, fresh), render::RenderPath::Fragment, &st);
  EXPECT_EQ(st.ray_texture_texels, 128 * 128);
  EXPECT_EQ(differing(both, rebuilt), 0u);
}

// Going back to an older spec of the same lineage (fewer strokes than held) rebuilds it: the
// held texture is never shown for a spec it does not belong to.
TEST(ray_texture, AnOlderSpecOfTheLineageIsRebuilt) {
  auto v = ml();
  test::TestVolume gv(v);
  const auto base =
      std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {64, 64}}}));
  const auto one = with_stroke(*base, stroke("termination", 0.5, 0.5, 0.2, 0.05));
  const Image first = test::render_gpu(gv, scene_of(*v, one), render::RenderPath::Fragment);
  const auto two = with_stroke(*one, stroke("termination", 0.2, 0.2, 0.2, 0.05));
  const Image second = test::render_gpu(gv, scene_of(*v, two), render::RenderPath::Fragment);
  EXPECT_GT(differing(first, second), 0u);
  render::RenderStats st;
  const Image again = test::render_gpu(gv, scene_of(*v, one), render::RenderPath::Fragment, &st);
  EXPECT_EQ(st.ray_texture_texels, 64 * 64);
  EXPECT_EQ(differing(first, again), 0u);
}

// A PNG of the defaults renders as no texture, pixel for pixel; a PNG written from painted
// strokes renders as those strokes do, within what 8 bits per channel keep.
TEST(ray_texture, PngTexturesRenderAsTheirStrokes) {
  auto v = ml();
  test::TestVolume gv(v);
  const auto dir = std::filesystem::temp_directory_path() / ("peakcast_rtpng_gpu_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Image none = test::render_gpu(gv, scene_of(*v, nullptr), render::RenderPath::Fragment);
  auto painted = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {64, 64}}}));
  const double termination = 1.0 - 1.0 / 255.0;
  write_ray_texture_png(build_ray_texture(*painted, termination), dir / "defaults.png");
  painted = with_stroke(*painted, stroke("step", 0.4, 0.5, 0.25, 0.25));
  painted = with_stroke(*painted, stroke("termination", 0.7, 0.4, 0.15, 0.2));
  painted = with_stroke(*painted, stroke("blend", 0.3, 0.75, 0.2, 0.7));
  write_ray_texture_png(build_ray_texture(*painted, termination), dir / "painted.png");
  const PngLocator here = [&](const std::string& p) { return dir / p; };
  auto from_png = [&](const char* name) {
    auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"png", name}}));
    return test::render_gpu(gv, scene_of(*v, load_ray_texture_png(spec, here)), render::RenderPath::Fragment);
  };
  EXPECT_EQ(differing(none, from_png("defaults.png")), 0u);
  const Image strokes = test::render_gpu(gv, scene_of(*v, painted), render::RenderPath::Fragment);
  const double psnr = reference::compare(from_png("painted.png"), strokes).psnr;
  const double moved = reference::compare(none, strokes).psnr;
  std::printf("PNG of the strokes vs the strokes: %.1f dB (the strokes vs no texture: %.1f dB)\n", psnr, moved);
  EXPECT_GE(psnr, 45.0);  // measured 54.9 dB
  EXPECT_LT(moved, 40.0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace peakcast
