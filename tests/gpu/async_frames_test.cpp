// The stream's asynchronous frames (Renderer::submit / collect): on GL a ring of pixel-buffer
// objects read back behind fences, on the CPU backend the default (drawn in submit). Either way
// a collected frame equals the same scene's 8-bit render() byte for byte, frames come back in
// the order submitted, and misuse is refused by name.
#include <stdexcept>

#include "gpu/gpu_fixture.h"

using namespace peakcast;
using nlohmann::json;

namespace {

ResolvedScene scene_at(const Volume& v, double azimuth, const std::string& classification, int w, int h) {
  const glm::dvec3 lo = v.origin, hi = v.origin + v.extent();
  Scene s = parse_scene({{"volume", "v"},
                         {"image", {{"width", w}, {"height", h}}},
                         {"render", {{"classification", classification}, {"shading", classification == "peaks"}}}});
  s.camera = default_camera(lo, hi, 30.0, azimuth, 20.0);
  return resolve_scene(s, v);
}

render::RenderRequest rgb8(bool samples) {
  render::RenderRequest r;
  r.output = render::RenderOutput::Rgb8;
  r.sample_stats = samples;
  return r;
}

}  // namespace

TEST(AsyncFrames, EqualTheSynchronousRenderInSubmissionOrder) {
  auto v = test::make_volume(GeneratorKind::Blobs, {40, 36, 32}, SourceType::U8, {1.0, 1.0, 1.25});
  test::TestVolume gv(v);
  auto& caster = *test::gpu().caster;
  // Different sizes and classifications in flight at once: each slot keeps its own frame.
  const std::vector<ResolvedScene> scenes = {scene_at(*v, 10, "post", 64, 48), scene_at(*v, 40, "peaks", 50, 70),
                                             scene_at(*v, 70, "preint", 64, 48), scene_at(*v, 100, "post", 33, 21)};
  std::vector<render::RenderResult> want;
  std::vector<render::RenderStats> want_stats;
  for (size_t i = 0; i < scenes.size(); ++i) {
    render::RenderStats st;
    want.push_back(caster.render(gv.get(), scenes[i], rgb8(i % 2 == 1), &st));
    want_stats.push_back(st);
  }
  size_t next = 0;
  for (size_t i = 0; i < scenes.size(); ++i) {
    caster.submit(gv.get(), scenes[i], rgb8(i % 2 == 1));
    if (caster.in_flight() < render::Renderer::kFramesInFlight) continue;
    render::RenderStats st;
    const render::RenderResult got = caster.collect(&st);
    EXPECT_EQ(got.rgb8.width, want[next].rgb8.width) << next;
    EXPECT_EQ(got.rgb8.height, want[next].rgb8.height) << next;
    EXPECT_EQ(got.rgb8.rgb, want[next].rgb8.rgb) << "frame " << next;
    EXPECT_EQ(st.variant, want_stats[next].variant);
    EXPECT_EQ(st.has_samples, next % 2 == 1);
    if (st.has_samples) {
      EXPECT_DOUBLE_EQ(st.samples_mean, want_stats[next].samples_mean);
    }
    if (!test::cpu_backend()) {
      EXPECT_GE(st.gpu_ms, 0.0);
    }
    ++next;
  }
  while (caster.in_flight() > 0) {
    const render::RenderResult got = caster.collect();
    EXPECT_EQ(got.rgb8.rgb, want[next].rgb8.rgb) << "frame " << next;
    ++next;
  }
  EXPECT_EQ(next, scenes.size());
}

TEST(AsyncFrames, MisuseIsRefusedByName) {
  auto v = test::make_volume(GeneratorKind::Blobs, {24, 24, 24}, SourceType::U8, {1.0, 1.0, 1.0});
  test::TestVolume gv(v);
  auto& caster = *test::gpu().caster;
  const ResolvedScene s = scene_at(*v, 30, "post", 16, 16);
  EXPECT_THROW(caster.collect(), std::logic_error);  // nothing submitted
  render::RenderRequest f = rgb8(false);
  f.output = render::RenderOutput::Float;
  EXPECT_THROW(caster.submit(gv.get(), s, f), std::invalid_argument);  // float frames: render()
  render::RenderRequest tile = rgb8(false);
  tile.tile = render::PixelRect{0, 0, 8, 8};
  EXPECT_THROW(caster.submit(gv.get(), s, tile), std::invalid_argument);
  for (size_t i = 0; i < render::Renderer::kFramesInFlight; ++i) caster.submit(gv.get(), s, rgb8(false));
  try {
    caster.submit(gv.get(), s, rgb8(false));
    ADD_FAILURE() << "a frame beyond the ring was taken";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("in flight"), std::string::npos) << e.what();
  }
  while (caster.in_flight() > 0) caster.collect();
  EXPECT_EQ(caster.in_flight(), 0u);
}
