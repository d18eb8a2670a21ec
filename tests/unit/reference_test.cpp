// The CPU reference against closed forms: a constant TF through a box seen orthographically
// along an axis has alpha = 1 - (1 - a)^(length / unit) exactly, whatever the step: each sample
// stands for its chord (the first half a step, the last up to the exit), and the chords add up
// to the ray's length in the box.
#include <gtest/gtest.h>

#include <cmath>

#include "core/generators.h"
#include "reference/reference_renderer.h"
#include "reference/field.h"
#include "reference/metrics.h"

using namespace peakcast;

namespace {

ResolvedScene constant_tf_scene(const Volume& v, double step) {
  nlohmann::json j = {{"volume", "x"},
                      {"image", {{"width", 8}, {"height", 8}}},
                      {"camera",
                       {{"eye", {100, 8, 8}},
                        {"center", {16, 8, 8}},
                        {"up", {0, 0, 1}},
                        {"projection", "orthographic"},
                        {"height", 8}}},
                      {"tf", {{"points", {{0.0, 1.0, 0.5, 0.25, 0.05}}}}},
                      {"render", {{"step", step}, {"early_termination", 1.0}}}};
  return resolve_scene(parse_scene(j), v);
}

Volume ramp() {
  GeneratorSpec g;
  g.kind = GeneratorKind::Ramp;
  g.dims = {33, 17, 17};  // box [0,32] x [0,16] x [0,16]
  g.type = SourceType::F32;
  return generate_volume(g);
}

TEST(Reference, LatticeSamplesIncludeEntryAndExit) {
  Volume v = ramp();
  for (double step : {1.0, 0.5, 4.0}) {
    Image img = reference::render_reference(v, constant_tf_scene(v, step));
    const double n = 32.0 / step + 1.0;  // t = 0, step, ..., 32
    const double alpha = 1.0 - std::pow(0.95, 32.0);
    EXPECT_NEAR(img.pixel(4, 4)[3], alpha, 1e-6) << step;
    EXPECT_NEAR(img.pixel(4, 4)[0], alpha * 1.0, 1e-6);
    EXPECT_NEAR(img.pixel(4, 4)[1], alpha * 0.5, 1e-6);
    EXPECT_EQ(img.samples[4 * 8 + 4], float(n));
  }
}

// render.clip: the span is cut before the lattice is laid, so a constant TF seen along x through
// what the clip keeps composites exactly the samples of the kept length, from the clipped entry.
TEST(Reference, ClipKeepsTheSpanItLeavesAndStartsTheLatticeThere) {
  Volume v = ramp();
  ResolvedScene s = constant_tf_scene(v, 1.0);  // eye on +x looking to -x: rays run x = 32 -> 0
  s.scene.render.clip =
      parse_clip(nlohmann::json::parse(R"({"plane": {"point": [10.5, 0, 0], "normal": [-1, 0, 0]}})"));
  Image img = reference::render_reference(v, s);
  // Kept: x <= 10.5, entered at x = 10.5: samples at 10.5, 9.5, ..., 0.5 (11 of them), standing
  // for the 10.5 units kept (the last for 0.5 before it and 0.5 after it).
  EXPECT_NEAR(img.pixel(4, 4)[3], 1.0 - std::pow(0.95, 10.5), 1e-6);
  EXPECT_EQ(img.samples[4 * 8 + 4], 11.f);
  // A crop box on y keeps the upper half of the 8-pixel window (y in [8, 12] world: rows 0-3).
  s.scene.render.clip = parse_clip(nlohmann::json::parse(R"({"box": [[-5, 8, -5], [40, 30, 40]]})"));
  img = reference::render_reference(v, s);
  EXPECT_GT(img.pixel(4, 4)[3], 0.5f);  // constant_tf_scene's up is +z: rows follow z, columns y
  int kept = 0;
  for (int x = 0; x < 8; ++x) kept += img.pixel(x, 4)[3] > 0.5f;
  EXPECT_EQ(kept, 4);
  EXPECT_EQ(img.samples[4 * 8 + 0] + img.samples[4 * 8 + 7], 33.f);  // one side has all 33, the other none
}

TEST(Reference, ConvergedEqualsTheContinuousIntegral) {
  Volume v = ramp();
  auto c = reference::render_converged(v, constant_tf_scene(v, 1.0), reference::OpticalModel::Dvr, 1e-6);
  EXPECT_NEAR(c.image.pixel(4, 4)[3], 1.0 - std::pow(0.95, 32.0), 1e-6);
}

TEST(Reference, TrilinearIsExactOnARampAndBSplineKeepsLinear) {
  Volume v = ramp();
  for (double x : {0.0, 3.25, 17.5, 31.99, 32.0}) {
    EXPECT_NEAR(reference::trilinear(v, {x, 5.5, 7.25}), x / 32.0, 1e-7);
    if (x > 1 && x < 31) {  // away from the clamped border the B-spline reproduces linears
      EXPECT_NEAR(reference::bspline(v, {x, 5.5, 7.25}), x / 32.0, 1e-6);
    }
  }
}

TEST(Metrics, PsnrOfKnownError) {
  Image a(4, 4), b(4, 4);
  for (size_t i = 0; i < b.rgba.size(); ++i) b.rgba[i] = i % 4 == 3 ? 0.f : 0.1f;
  auto e = reference::compare(a, b);
  EXPECT_NEAR(e.rmse, 0.1, 1e-7);
  EXPECT_NEAR(e.psnr, 20.0, 1e-5);
  EXPECT_NEAR(e.max_abs, 0.1, 1e-7);
  EXPECT_EQ(e.share_off, 1.0);
  EXPECT_THROW(reference::compare(a, Image(3, 4)), std::invalid_argument);
}

}  // namespace
