// The scenes and checks the sampling tests share (sampling_test.cpp, virtual_samples_test.cpp):
// Marschner-Lobb 41^3 with a smooth band TF, a close-up and a far camera, and the GPU-against-
// CPU-twin check.
#pragma once

#include <string>
#include <vector>

#include "gpu/gpu_fixture.h"
#include "reference/reference_renderer.h"
#include "unit/test_util.h"

namespace peakcast::sampling_scenes {

using nlohmann::json;

inline std::shared_ptr<Volume> ml() {
  return test::make_volume(GeneratorKind::MarschnerLobb, {41, 41, 41}, SourceType::F32);
}

// A smooth band TF over the Marschner-Lobb range [0, 1].
inline const json kBandTf = {
    {"points",
     {{0.0, 0.1, 0.2, 0.8, 0.0}, {0.45, 0.3, 0.6, 0.9, 0.05}, {0.6, 0.9, 0.6, 0.3, 0.35}, {1.0, 1.0, 1.0, 1.0, 0.0}}}};

// Close-up (Knoll Fig. 6 style): the eye just outside a corner of the box, wide angle, so the
// near samples cover many pixels and the far ones few.
inline json close_camera() {
  return {{"eye", {46, 43, 47}}, {"center", {20, 20, 20}}, {"up", {0, 1, 0}}, {"fov_y", 50}};
}
inline json far_camera() {
  return {{"eye", {110, 85, 140}}, {"center", {20, 20, 20}}, {"up", {0, 1, 0}}, {"fov_y", 30}};
}

inline json scene_json(json camera, json render, int size = 64) {
  render["early_termination"] = 1.0;
  return {{"image", {{"width", size}, {"height", size}}}, {"camera", camera}, {"tf", kBandTf}, {"render", render}};
}

inline double mean_samples(const Image& img) {
  double n = 0, sum = 0;
  for (float s : img.samples)
    if (s >= 0) sum += s, n += 1;
  return n ? sum / n : 0.0;
}

struct Twin {
  std::string name;
  json camera, render;
};

// Measured on llvmpipe (Mesa 22.3.6): 120-131 dB for every case (the same lattice, float against
// double); a lattice 5% off gives 31-36 dB, a wrong adaptive coverage 33 dB. The bound leaves
// room for other GPUs' filtering precision (the uniform GpuVsCpu cases sit at 58-80 dB).
constexpr double kMinTwinPsnr = 50.0;

// Each case rendered by the GL ray caster and by its CPU twin at the same settings; the variant
// must contain `marker`.
inline void check_twins(const Volume& v, const render::ResidentVolume& gv, const std::vector<Twin>& twins,
                        const std::string& marker) {
  for (const auto& t : twins) {
    const ResolvedScene s = test::make_scene(v, scene_json(t.camera, t.render));
    render::RenderStats st;
    const Image g = test::render_gpu(gv, s, render::RenderPath::Fragment, &st);
    const Image c = reference::render_reference(v, s);
    const auto e = reference::compare(g, c);
    std::printf("%-30s %-40s PSNR %.1f dB, samples/ray GPU %.1f CPU %.1f\n", t.name.c_str(), st.variant.c_str(), e.psnr,
                mean_samples(g), mean_samples(c));
    EXPECT_NE(st.variant.find(marker), std::string::npos) << t.name;
    EXPECT_GE(e.psnr, kMinTwinPsnr) << t.name;
    if (e.psnr < kMinTwinPsnr) test::save_artifacts(g, c, "twin");
    EXPECT_NEAR(mean_samples(g), mean_samples(c), 0.02 * mean_samples(c) + 0.5) << t.name;
  }
}

}  // namespace peakcast::sampling_scenes
