// render.clip (core/clip.h) on the backend under test (GL, or the CPU backend as cpu.Clip.*):
// every method with a crop box and a plane against the CPU reference of the same clipped scene;
// a box covering the volume changes no pixel; clipped space contributes nothing.
#include <cmath>

#include <glm/geometric.hpp>

#include "gpu/gpu_fixture.h"
#include "reference/reference_renderer.h"
#include "reference/metrics.h"
#include "unit/test_util.h"

using namespace peakcast;
using nlohmann::json;

namespace {

std::shared_ptr<Volume> blobs() {
  return test::make_volume(GeneratorKind::Blobs, {48, 40, 44}, SourceType::U8, {1, 1.25, 1});
}

// A TF over the blobs' range with a band (DVR) and an opacity peak at 0.6 (peak finding).
json tf_for(const Volume& v) {
  auto at = [&](double f) { return v.min_value + f * (v.max_value - v.min_value); };
  return {{"points",
           {{at(0.0), 0, 0, 0, 0},
            {at(0.2), 0.9, 0.5, 0.2, 0.0},
            {at(0.45), 0.9, 0.7, 0.4, 0.25},
            {at(0.55), 0.3, 0.6, 1.0, 0.05},
            {at(0.6), 1.0, 1.0, 0.8, 0.9},
            {at(0.65), 0.3, 0.6, 1.0, 0.05},
            {at(1.0), 1, 1, 1, 0.6}}}};
}

json camera_for(const Volume& v) {
  const glm::dvec3 c = v.origin + v.extent() * 0.5, eye = c + glm::dvec3(60, -70, 90);
  return {{"eye", {eye.x, eye.y, eye.z}}, {"center", {c.x, c.y, c.z}}, {"up", {0, 0, 1}}, {"fov_y", 35}};
}

// A crop box cutting a corner off on two axes and an oblique plane through the centre.
json clip_for(const Volume& v) {
  const glm::dvec3 lo = v.origin, hi = v.origin + v.extent(), c = (lo + hi) * 0.5;
  return {{"box", {{lo.x - 1, lo.y + 0.3 * (hi.y - lo.y), lo.z - 1}, {hi.x + 1, hi.y + 1, lo.z + 0.8 * (hi.z - lo.z)}}},
          {"plane", {{"point", {c.x, c.y, c.z}}, {"normal", {-1.0, 0.3, 0.4}}}}};
}

struct Method {
  const char* name;
  json render;
  double min_psnr;  // measured on llvmpipe and the CPU backend, less a margin (see below)
};

// Measured against the clipped reference: GL on llvmpipe (Mesa 22.3.6) 53.3-60.9 dB (post 54.1,
// preint 60.9, peaks shaded 57.5, differential 53.3, virtual samples 56.4, adaptive 53.3,
// tricubic 56.7); the CPU backend 113-138 dB. An image that ignores the clip scores 13.7-16.9 dB.
// The bound leaves room for other GPUs' filtering precision (as raycast_vs_cpu_test's 50 dB).
std::vector<Method> methods() {
  return {
      {"post", {{"classification", "post"}}, 45},
      {"preint", {{"classification", "preint"}}, 45},
      {"peaks_shaded", {{"classification", "peaks"}, {"shading", true}}, 45},
      {"differential", {{"sampling", "differential"}, {"s_k", 2}}, 45},
      {"virtual_samples", {{"virtual_samples", 3}, {"step", 2.0}}, 45},
      {"adaptive", {{"adaptive", true}}, 45},
      {"tricubic", {{"filter", "tricubic"}}, 45},
  };
}

TEST(Clip, EveryMethodMatchesTheReference) {
  auto v = blobs();
  test::TestVolume gv(v);
  for (const Method& m : methods()) {
    json render = m.render;
    render["clip"] = clip_for(*v);
    const ResolvedScene clipped =
        test::make_scene(*v, {{"tf", tf_for(*v)}, {"camera", camera_for(*v)}, {"render", render}});
    render.erase("clip");
    const ResolvedScene whole =
        test::make_scene(*v, {{"tf", tf_for(*v)}, {"camera", camera_for(*v)}, {"render", render}});
    const Image g = test::render_gpu(gv, clipped, render::RenderPath::Fragment);
    const Image ref = reference::render_reference(*v, clipped);
    const Image unclipped = test::render_gpu(gv, whole, render::RenderPath::Fragment);
    const auto e = reference::compare(g, ref);
    const auto cut = reference::compare(unclipped, ref);
    std::printf("%-16s clipped vs reference: PSNR %.1f dB, max %.4f; the unclipped image: %.1f dB\n", m.name, e.psnr,
                e.max_abs, cut.psnr);
    EXPECT_GE(e.psnr, m.min_psnr) << m.name;
    EXPECT_LT(cut.psnr, 30.0) << m.name << ": the clip must change the picture, or this proves nothing";
    if (e.psnr < m.min_psnr) test::save_artifacts(g, ref, std::string("clip_") + m.name);
  }
}

TEST(Clip, ABoxCoveringTheVolumeChangesNoPixel) {
  auto v = blobs();
  test::TestVolume gv(v);
  const glm::dvec3 lo = v->origin, hi = v->origin + v->extent();
  for (const Method& m : methods()) {
    json render = m.render;
    const ResolvedScene plain =
        test::make_scene(*v, {{"tf", tf_for(*v)}, {"camera", camera_for(*v)}, {"render", render}});
    render["clip"] = {{"box", {{lo.x - 2, lo.y - 2, lo.z - 2}, {hi.x + 2, hi.y + 2, hi.z + 2}}},
                      {"plane", {{"point", {lo.x - 1, 0, 0}}, {"normal", {1, 0, 0}}}}};  // keeps all of it
    const ResolvedScene covered =
        test::make_scene(*v, {{"tf", tf_for(*v)}, {"camera", camera_for(*v)}, {"render", render}});
    for (auto path : {render::RenderPath::Fragment, render::RenderPath::Compute}) {
      const auto e = reference::compare(test::render_gpu(gv, covered, path), test::render_gpu(gv, plain, path));
      EXPECT_EQ(e.max_abs, 0.0) << m.name;
    }
  }
}

TEST(Clip, ClippedSpaceContributesNothing) {
  // A ramp along x (value x / 32): the TF is opaque below 0.45 only, and the plane keeps x >= 16
  // (values >= 0.5): nothing is left to draw, whichever method; without the plane, plenty.
  auto v = test::make_volume(GeneratorKind::Ramp, {33, 17, 17}, SourceType::F32);
  test::TestVolume gv(v);
  const json tf = {
      {"points", {{0.0, 1, 0.5, 0.2, 0.8}, {0.45, 1, 0.5, 0.2, 0.8}, {0.46, 0, 0, 0, 0}, {1.0, 0, 0, 0, 0}}}};
  const json camera = {{"eye", {-30, -40, 50}}, {"center", {16, 8, 8}}, {"up", {0, 0, 1}}, {"fov_y", 40}};
  for (const Method& m : methods()) {
    json render = m.render;
    const ResolvedScene whole = test::make_scene(*v, {{"tf", tf}, {"camera", camera}, {"render", render}});
    render["clip"] = {{"plane", {{"point", {16, 0, 0}}, {"normal", {1, 0, 0}}}}};
    const ResolvedScene clipped = test::make_scene(*v, {{"tf", tf}, {"camera", camera}, {"render", render}});
    double most = 0, most_whole = 0;
    for (auto path : {render::RenderPath::Fragment, render::RenderPath::Compute}) {
      const Image c = test::render_gpu(gv, clipped, path), w = test::render_gpu(gv, whole, path);
      for (size_t i = 3; i < c.rgba.size(); i += 4) {
        most = std::max<double>(most, c.rgba[i]);
        most_whole = std::max<double>(most_whole, w.rgba[i]);
      }
    }
    EXPECT_EQ(most, 0.0) << m.name;
    EXPECT_GT(most_whole, 0.5) << m.name;
  }
}

}  // namespace
