// The stiff suite's exact cases (ctest label `stiff`): the CPU reference itself on scenes whose
// answer is known in closed form, a linear ramp through a step TF and Dirac peaks on a cone
// field. The table of stiff and extreme cases is stiff_test.cpp.
#include <cmath>

#include "core/generators.h"
#include "core/scene.h"
#include "core/volume_io.h"
#include "reference/ray_events.h"
#include "reference/reference_renderer.h"
#include "unit/test_util.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

Volume generated(GeneratorKind kind, Dims dims) {
  GeneratorSpec g;
  g.kind = kind;
  g.dims = dims;
  g.type = SourceType::F32;
  return generate_volume(g);
}

// A linear ramp (x / 32 over [0, 32]) seen along x through a step TF: opacity 0.1 per unit for
// values >= 1/2, so every ray crosses 16 units of it: alpha = 1 - 0.9^16, colour alpha x rgb.
TEST(stiff_reference, LinearRampThroughAStepTfIsExact) {
  const Volume v = generated(GeneratorKind::Ramp, {33, 17, 17});
  const json scene = {
      {"volume", "x"},
      {"image", {{"width", 8}, {"height", 8}}},
      {"camera",
       {{"eye", {100, 8, 8}},
        {"center", {16, 8, 8}},
        {"up", {0, 0, 1}},
        {"projection", "orthographic"},
        {"height", 8}}},
      {"tf",
       {{"points", {{0.0, 0, 0, 0, 0}, {0.5, 0, 0, 0, 0}, {0.5, 1.0, 0.5, 0.25, 0.1}, {1.0, 1.0, 0.5, 0.25, 0.1}}}}},
      {"render", {{"early_termination", 1.0}}}};
  const auto c =
      reference::render_converged(v, resolve_scene(parse_scene(scene), v), reference::OpticalModel::Dvr, 1e-7);
  const double a = 1.0 - std::pow(0.9, 16.0);
  for (int y : {0, 3, 7})
    for (int x : {0, 4, 7}) {
      const float* p = c.image.pixel(x, y);
      EXPECT_NEAR(p[3], a, 1e-6);
      EXPECT_NEAR(p[0], a * 1.0, 1e-6);
      EXPECT_NEAR(p[1], a * 0.5, 1e-6);
      EXPECT_NEAR(p[2], a * 0.25, 1e-6);
    }
}

// A cone field 1 - |x - c| / 16 (the sphere generator, 33^3) with Dirac peaks at 0.5 (red,
// opacity 0.5) and 0.75 (blue, 0.5): along grid lines through voxel centres the trilinear field
// is piecewise linear, so the crossings are known exactly, and so is the composited colour.
TEST(stiff_reference, SphereWithDiracPeaksHasExactHitsAndColours) {
  const Volume v = generated(GeneratorKind::Sphere, {33, 33, 33});
  const double w = 1e-7;
  const json tf = {{"points",
                    {{0.0, 0, 0, 0, 0},
                     {0.5 - w, 0, 0, 0, 0},
                     {0.5, 1, 0, 0, 0.5},
                     {0.5 + w, 0, 0, 0, 0},
                     {0.75 - w, 0, 0, 0, 0},
                     {0.75, 0, 0, 1, 0.5},
                     {0.75 + w, 0, 0, 0, 0},
                     {1.0, 0, 0, 0, 0}}}};
  // Exact crossings along the central line y = z = 16, entering at x = 32: 0.5 at x = 24 and 8,
  // 0.75 at x = 20 and 12 (box-centred: +8, -8, +4, -4). Each lies on a voxel (a cell face): the
  // rising 0.75 was lost between two cells until the reference kept the sampled value there.
  Ray r;
  r.o = {30, 0, 0};
  r.d = {-1, 0, 0};
  const glm::dvec3 half(16, 16, 16);
  double t0 = 0, t1 = 0;
  ASSERT_TRUE(intersect_box(r, half, t0, t1));
  const auto split = reference::split_ray(v, Filter::Trilinear, r, half, t0, t1, {}, {0.5, 0.75});
  ASSERT_EQ(split.peaks.size(), 4u);
  const double expect_t[] = {22, 26, 34, 38}, expect_v[] = {0.5, 0.75, 0.75, 0.5};
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(split.peaks[i].t, expect_t[i], 1e-9) << i;
    EXPECT_EQ(split.peaks[i].value, expect_v[i]) << i;
  }
  // The image: pixel p's ray runs along the grid line y = 16 + (p - 16) (pixels of 1 unit).
  const json scene = {{"volume", "x"},
                      {"image", {{"width", 33}, {"height", 33}}},
                      {"camera",
                       {{"eye", {100, 16, 16}},
                        {"center", {16, 16, 16}},
                        {"up", {0, 0, 1}},
                        {"projection", "orthographic"},
                        {"height", 33}}},
                      {"tf", tf},
                      {"render", {{"classification", "peaks"}, {"early_termination", 1.0}}}};
  const auto c =
      reference::render_converged(v, resolve_scene(parse_scene(scene), v), reference::OpticalModel::Peaks, 1e-6);
  for (int p = 0; p < 33; ++p) {
    const int d = std::abs(p - 16);
    const float* px = c.image.pixel(p, 16);
    if (d <= 3) {  // red, blue, blue, red: (0.5625, 0, 0.375), alpha 0.9375
      EXPECT_NEAR(px[0], 0.5625, 1e-5) << p;
      EXPECT_NEAR(px[2], 0.375, 1e-5) << p;
      EXPECT_NEAR(px[3], 0.9375, 1e-5) << p;
    } else if (d >= 5 && d <= 7) {  // red twice
      EXPECT_NEAR(px[0], 0.75, 1e-5) << p;
      EXPECT_NEAR(px[2], 0.0, 1e-5) << p;
      EXPECT_NEAR(px[3], 0.75, 1e-5) << p;
    } else if (d >= 9) {
      EXPECT_NEAR(px[3], 0.0, 1e-5) << p;
    }
  }
}

}  // namespace
}  // namespace peakcast
