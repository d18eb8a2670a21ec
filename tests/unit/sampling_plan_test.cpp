// What s_k means (docs/scenes.md "Sampling"): differential sampling's step where a ray crosses
// the focal plane is s_k times a pixel diagonal's footprint there. Counted on the lattice itself
// (core/sampling.h), which the GL shader and the CPU backend mirror (tests/gpu/sampling_test.cpp
// holds them to it).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>

#include "core/generators.h"
#include "core/sampling.h"
#include "core/scene.h"

using namespace peakcast;

namespace {

const double kPi = std::acos(-1.0);
// The eye's distance from the box centre on a close-up: 1.3 times the box's half diagonal
// (54.6), as tests/gpu's close camera (1.27).
const double kClose = 71.0;

Volume cube() {
  GeneratorSpec g;
  g.kind = GeneratorKind::Blobs;
  g.dims = {64, 64, 64};
  return generate_volume(g);
}

// A close-up: the eye `distance` from the box centre along a diagonal, the focal point at the
// centre, `fov` degrees.
ResolvedScene close_up(const Volume& v, double s_k, double distance, double fov) {
  const glm::dvec3 c(31.5), eye = c + distance * glm::normalize(glm::dvec3(0.6, 0.5, 0.62));
  const std::string text = R"({"volume": "v", "image": {"width": 64, "height": 64},
    "camera": {"eye": [)" + std::to_string(eye.x) +
                           "," + std::to_string(eye.y) + "," + std::to_string(eye.z) +
                           R"(], "center": [31.5, 31.5, 31.5], "up": [0, 0, 1], "fov_y": )" + std::to_string(fov) +
                           R"(}, "render": {"sampling": "differential", "s_k": )" + std::to_string(s_k) + "}}";
  return resolve_scene(parse_scene_text(text), v);
}

struct Rays {
  ViewSetup view;
  glm::dvec3 half;
};

Rays rays_of(const ResolvedScene& s) {
  return {setup_view(s.camera, (s.box_min + s.box_max) * 0.5, s.scene.width, s.scene.height),
          (s.box_max - s.box_min) * 0.5};
}

// Mean lattice points per ray over the pixels whose ray meets the box.
double samples_per_ray(const ResolvedScene& s) {
  const SamplingPlan plan = plan_sampling(s);
  const Rays rs = rays_of(s);
  double sum = 0;
  int hits = 0;
  for (int y = 0; y < s.scene.height; ++y)
    for (int x = 0; x < s.scene.width; ++x) {
      const Ray r = make_ray(rs.view, x, y);
      double t0, t1;
      if (!intersect_box(r, rs.half, t0, t1)) continue;
      t0 = std::max(t0, r.t_eye);
      if (t1 <= t0) continue;
      const RayLattice l = ray_lattice(plan, rs.view, r, t0);
      sum += std::floor(l.index_at(t1)) + 1;
      ++hits;
    }
  return sum / std::max(hits, 1);
}

TEST(SamplingPlan, TheStepAtTheFocalPlaneIsSkFootprints) {
  const Volume v = cube();
  for (double s_k : {0.125, 0.5, 1.0, 4.0}) {
    const ResolvedScene s = close_up(v, s_k, kClose, 40.0);
    const SamplingPlan plan = plan_sampling(s);
    ASSERT_TRUE(plan.differential);
    // The footprint of a pixel's diagonal at the focal distance.
    const double pixel = 2 * kClose * std::tan(20.0 * kPi / 180) / 64;
    EXPECT_NEAR(plan.footprint / (std::sqrt(2.0) * pixel), 1.0, 1e-6);
    // The central pixel's ray (one half pixel off the axis: 64 is even) where it crosses the focal plane.
    const Rays rs = rays_of(s);
    const Ray r = make_ray(rs.view, 32, 32);
    double t0, t1;
    ASSERT_TRUE(intersect_box(r, rs.half, t0, t1));
    const RayLattice l = ray_lattice(plan, rs.view, r, std::max(t0, r.t_eye));
    const double t_focus = r.t_eye + kClose / glm::dot(r.d, rs.view.forward);
    const double step = l.step(l.index_at(t_focus), 1);
    EXPECT_NEAR(step / (s_k * plan.footprint), 1.0, 0.02) << "s_k " << s_k;
  }
}

TEST(SamplingPlan, QuarteringSkQuadruplesTheSamples) {
  const Volume v = cube();
  const double fine = samples_per_ray(close_up(v, 0.125, kClose, 40.0));
  const double coarse = samples_per_ray(close_up(v, 0.5, kClose, 40.0));
  std::printf("samples per ray: s_k 0.125 %.1f, s_k 0.5 %.1f\n", fine, coarse);
  EXPECT_GE(fine / coarse, 3.2) << fine << " / " << coarse;
  EXPECT_LE(fine / coarse, 4.8) << fine << " / " << coarse;
}

TEST(SamplingPlan, AnEyeTwiceAsFarFramingTheSameFocalPlaneSamplesAlike) {
  const Volume v = cube();
  const double near_fov = 40.0, far_fov = 2 * std::atan(std::tan(near_fov * kPi / 360) / 2) * 180 / kPi;
  for (double s_k : {0.125, 0.5, 2.0}) {
    const double near = samples_per_ray(close_up(v, s_k, kClose, near_fov));
    const double far = samples_per_ray(close_up(v, s_k, 2 * kClose, far_fov));
    std::printf("s_k %g: samples per ray %.1f, eye twice as far %.1f\n", s_k, near, far);
    EXPECT_NEAR(far / near, 1.0, 0.2) << "s_k " << s_k << ": " << near << " and " << far;
  }
}

}  // namespace
