// Differential and adaptive sampling (Knoll §5, §6.2): the GL ray caster against its
// CPU twin at the same settings, both against the converged reference; differential against
// uniform on a close-up camera at an equal sample budget; the s_k sweep; adaptive sampling on a
// constant volume; orthographic "differential" is uniform at the footprint.
#include <cmath>
#include <cstring>
#include <tuple>

#include <glm/geometric.hpp>

#include "core/sampling.h"
#include "gpu/gpu_fixture.h"
#include "reference/reference_renderer.h"
#include "gpu/sampling_scenes.h"

using namespace peakcast;
using nlohmann::json;
using namespace peakcast::sampling_scenes;

namespace {

TEST(Differential, GpuMatchesTheCpuTwin) {
  auto v = ml();
  test::TestVolume gv(v);
  const std::vector<Twin> twins = {
      {"close post trilinear", close_camera(), {{"sampling", "differential"}, {"s_k", 2}}},
      {"far post trilinear", far_camera(), {{"sampling", "differential"}, {"s_k", 2}}},
      {"close post tricubic", close_camera(), {{"sampling", "differential"}, {"s_k", 2}, {"filter", "tricubic"}}},
      {"close peaks", close_camera(), {{"sampling", "differential"}, {"s_k", 2}, {"classification", "peaks"}}},
      {"close preint", close_camera(), {{"sampling", "differential"}, {"s_k", 2}, {"classification", "preint"}}},
      {"close shading, no skipping",
       close_camera(),
       {{"sampling", "differential"}, {"s_k", 1}, {"shading", true}, {"space_skipping", false}}},
  };
  check_twins(*v, gv, twins, "+diff");
}

TEST(Differential, StepGrowsAlongTheRayAndEntersCellsWithoutResampling) {
  auto v = ml();
  const ResolvedScene s = test::make_scene(*v, scene_json(close_camera(), {{"sampling", "differential"}, {"s_k", 4}}));
  const SamplingPlan plan = plan_sampling(s);
  ASSERT_TRUE(plan.differential);
  const ViewSetup view = setup_view(s.camera, (s.box_min + s.box_max) * 0.5, s.scene.width, s.scene.height);
  const Ray r = make_ray(view, 32, 32);
  double t0, t1;
  ASSERT_TRUE(intersect_box(r, (s.box_max - s.box_min) * 0.5, t0, t1));
  const RayLattice l = ray_lattice(plan, view, r, t0);
  EXPECT_GT(l.A, 0.0);
  double prev_step = 0;
  for (int j = 0; j < 50; ++j) {
    const double step = l.t(j + 1) - l.t(j);
    EXPECT_NEAR(step, l.step(j, 1), 1e-9);
    EXPECT_NEAR(step - prev_step, j ? l.A : step, 1e-9);  // grows by a per sample (eq. 17)
    EXPECT_NEAR(l.index_at(l.t(j)), j, 1e-6);             // eq. 18 inverts the lattice
    prev_step = step;
  }
  // A cell entered at any t restarts at the first lattice index at or after it: never one
  // that was sampled already, never one skipped.
  for (double t : {t0 + 0.3, t0 + 7.77, t0 + 20.0}) {
    const double x = l.index_at(t);
    EXPECT_GE(l.t(std::ceil(x)), t - 1e-9);
    EXPECT_LT(l.t(std::ceil(x) - 1), t);
  }
}

// Knoll §7.2 / Table 2: differential against uniform sampling on a close-up at the same cost.
// Cost is the mean number of samples per ray (the machine-independent part of frame time); the
// uniform step is matched to the differential run's count. The judge is the converged image.
struct EqualCost {
  double samples, psnr_diff, psnr_uniform, uniform_step;
};

EqualCost differential_vs_uniform(const Volume& v, const render::ResidentVolume& gv, json tf, double sk,
                                  bool early_termination) {
  json dj = scene_json(close_camera(), {{"sampling", "differential"}, {"s_k", sk}}, 96);
  dj["tf"] = tf;
  if (early_termination) dj["render"].erase("early_termination");
  const ResolvedScene sd = test::make_scene(v, dj);
  const auto conv = reference::render_converged(v, sd, reference::OpticalModel::Dvr, 1e-4);
  EXPECT_TRUE(conv.converged);
  const Image d = test::render_gpu(gv, sd, render::RenderPath::Fragment);
  EqualCost r{mean_samples(d), reference::compare(d, conv.image).psnr, 0, 1.0};
  for (int k = 0; k < 5; ++k) {  // match the sample count (within 2%)
    json uj = dj;
    uj["render"].erase("sampling");
    uj["render"]["step"] = r.uniform_step;
    const Image u = test::render_gpu(gv, test::make_scene(v, uj), render::RenderPath::Fragment);
    r.psnr_uniform = reference::compare(u, conv.image).psnr;
    const double ratio = mean_samples(u) / r.samples;
    if (std::abs(ratio - 1.0) < 0.02) break;
    r.uniform_step *= ratio;
  }
  return r;
}

TEST(Differential, AgainstUniformOnACloseUpAtEqualSamples) {
  auto v = ml();
  test::TestVolume gv(v);
  const json opaque = {
      {"points",
       {{0.0, 0.1, 0.2, 0.8, 0.0}, {0.45, 0.3, 0.6, 0.9, 0.15}, {0.6, 0.9, 0.6, 0.3, 1.0}, {1.0, 1.0, 1.0, 1.0, 0.0}}}};
  std::printf("%-22s %5s %9s %12s %12s %10s\n", "scene", "s_k", "samples", "diff_dB", "uniform_dB", "step_u");
  for (const auto& [name, tf, et] :
       {std::tuple{"band", kBandTf, false}, std::tuple{"opaque, early stop", opaque, true}})
    // s_k 1.5 and 4 put the step at the focal plane at 1.5 and 4 pixel footprints: about the
    // sample budgets (75 and 18 per ray) at which the bound below was measured.
    for (double sk : {1.5, 4.0}) {
      const EqualCost r = differential_vs_uniform(*v, gv, tf, sk, et);
      std::printf("%-22s %5.1f %9.1f %12.2f %12.2f %10.3f\n", name, sk, r.samples, r.psnr_diff, r.psnr_uniform,
                  r.uniform_step);
      // Measured on llvmpipe: differential 0.1-0.75 dB below uniform at the same sample count.
      // Knoll's construction (eq. 14-17) grows the step by a = k |dD/dx| per sample, a few per
      // cent over these rays, so it samples almost uniformly at the footprint-derived step; the
      // per-ray converged image rewards no particular depth. The bound catches a broken lattice
      // (a skipped or doubled sample costs several dB), not a win the method does not have here.
      EXPECT_GT(r.psnr_diff, r.psnr_uniform - 1.0) << name << " s_k " << sk;
      EXPECT_GT(r.psnr_diff, 30.0) << name << " s_k " << sk;
    }
}

// Knoll Fig. 6 / Table 2 on the vessel volume: a close-up of the tree (tissue clear, lumen
// semi-transparent or nearly opaque), 128^2, space skipping on. Cost is what the GPU visits:
// samples per ray after skipping, the part of frame time the method controls (`peakcast bench
// sampling` prints frame times). The uniform step is matched to the differential run's count.
TEST(Differential, AgainstUniformAtEqualCostOnAVesselCloseUp) {
  auto v = test::make_volume(GeneratorKind::Vessels, {96, 96, 96}, SourceType::U16);
  test::TestVolume gv(v);
  const double lo = v->min_value, hi = v->max_value, r = 0.5 * std::sqrt(3.0) * 95.0;
  const glm::dvec3 c(47.5), eye = c + 1.05 * r * glm::normalize(glm::dvec3(0.55, 0.45, 0.7));
  std::printf("%-8s %5s %9s %12s %12s %10s\n", "lumen", "s_k", "samples", "diff_dB", "uniform_dB", "step_u");
  for (const auto& [name, mid, top] : {std::tuple{"0.3-0.6", 0.3, 0.6}, std::tuple{"0.8-1.0", 0.8, 1.0}}) {
    json base = {
        {"image", {{"width", 128}, {"height", 128}}},
        {"camera", {{"eye", {eye.x, eye.y, eye.z}}, {"center", {c.x, c.y, c.z}}, {"up", {0, 1, 0}}, {"fov_y", 60}}},
        {"tf",
         {{"points",
           {{lo, 0, 0, 0, 0},
            {lo + 0.3 * (hi - lo), 0.2, 0.4, 1.0, 0.0},
            {lo + 0.6 * (hi - lo), 1.0, 0.8, 0.4, mid},
            {hi, 1, 1, 1, top}}}}},
        {"render", {{"early_termination", 1.0}}}};
    const auto conv = reference::render_converged(*v, test::make_scene(*v, base), reference::OpticalModel::Dvr, 1e-4);
    ASSERT_TRUE(conv.converged);
    for (double sk : {2.0, 1.0, 0.5, 0.25}) {
      json dj = base;
      dj["render"]["sampling"] = "differential";
      dj["render"]["s_k"] = sk;
      render::RenderStats sd, su;
      const Image d = test::render_gpu(gv, test::make_scene(*v, dj), render::RenderPath::Fragment, &sd);
      const double psnr_d = reference::compare(d, conv.image).psnr;
      double step = 1.0, psnr_u = 0.0;
      for (int k = 0; k < 6; ++k) {  // match the visited samples per ray (within 2%)
        json uj = base;
        uj["render"]["step"] = step;
        const Image u = test::render_gpu(gv, test::make_scene(*v, uj), render::RenderPath::Fragment, &su);
        psnr_u = reference::compare(u, conv.image).psnr;
        const double ratio = su.samples_mean / sd.samples_mean;
        if (std::abs(ratio - 1.0) < 0.02) break;
        step *= ratio;
      }
      std::printf("%-8s %5.2f %9.1f %12.2f %12.2f %10.3f\n", name, sk, sd.samples_mean, psnr_d, psnr_u, step);
      // Measured on llvmpipe: differential -0.7 ... +1.0 dB against uniform at equal cost (the
      // per-ray converged image weighs every depth alike; see the README). Knoll's "lower
      // error at equal frame time" does not hold by this measure; the bound catches a broken
      // lattice (a skipped or doubled sample costs several dB).
      EXPECT_GT(psnr_d, psnr_u - 1.5) << name << " s_k " << sk;
      EXPECT_GT(psnr_d, 24.0) << name << " s_k " << sk;
    }
  }
}

// s_k from 1e3 to 1e-3: every image finite, the samples bounded by the minimum step, and the
// error falling as s_k falls until the minimum step takes over.
TEST(Differential, SkSweepIsStableAndConverges) {
  auto v = ml();
  test::TestVolume gv(v);
  const ResolvedScene s0 = test::make_scene(*v, scene_json(close_camera(), {}, 48));
  const auto conv = reference::render_converged(*v, s0, reference::OpticalModel::Dvr, 1e-4);
  ASSERT_TRUE(conv.converged);
  const double diag = glm::length(s0.box_max - s0.box_min);
  const double max_samples = diag / (kMinDifferentialStepFraction * s0.min_spacing) + 2;
  std::printf("%8s %10s %10s %10s %8s\n", "s_k", "samples", "max", "RMSE", "ms");
  std::vector<double> rmse;
  const std::vector<double> sks = {1e3, 1e2, 10, 1, 0.1, 1e-2, 1e-3};
  for (double sk : sks) {
    const ResolvedScene s =
        test::make_scene(*v, scene_json(close_camera(), {{"sampling", "differential"}, {"s_k", sk}}, 48));
    render::RenderStats st;
    const Image g = test::render_gpu(gv, s, render::RenderPath::Fragment, &st);
    ASSERT_TRUE(test::all_finite(g)) << "s_k " << sk;
    const auto e = reference::compare(g, conv.image);
    rmse.push_back(e.rmse);
    std::printf("%8g %10.1f %10.0f %10.3e %8.1f\n", sk, st.samples_mean, st.samples_max, e.rmse, st.render_ms);
    EXPECT_LE(st.samples_max, max_samples) << "s_k " << sk;
    EXPECT_EQ(st.rays_at_cap, 0);
  }
  // Falling all the way (each at most 5% above the one before: 1e3 and 1e2 both take one sample
  // per ray) down to the floor: from s_k ~ 0.01 the minimum step holds the first step, and the
  // error (9.1e-5 and 9.6e-5 at s_k 0.01 and 0.001, measured on llvmpipe) is the float
  // arithmetic's and the converged reference's (tolerance 1e-4), where it only has to stay.
  const double floor = 2e-4;
  for (size_t i = 1; i < rmse.size(); ++i) {
    if (rmse[i - 1] > floor)
      EXPECT_LT(rmse[i], rmse[i - 1] * 1.05) << "s_k " << sks[i];
    else
      EXPECT_LT(rmse[i], floor) << "s_k " << sks[i];
  }
  EXPECT_LT(rmse.back(), rmse.front() * 0.01);
}

// The per-ray cap: a 1199-voxel-long ray at the smallest legal step (1e-3 voxel) wants 1.2 M
// samples. It stops at the cap (kMaxSamplesPerRay; on llvmpipe, which ends a shader's loops
// after 65535 iterations in all, a lower one), the stats say so, and the image stays finite.
// Under the cap every sample is taken: nothing is cut silently.
TEST(Sampling, PerRayCapIsReportedWhenHit) {
  auto v = test::make_volume(GeneratorKind::Ramp, {2, 2, 1200}, SourceType::F32);
  test::TestVolume gv(v);
  json sj = {{"image", {{"width", 2}, {"height", 2}}},
             {"camera", {{"eye", {0.5, 0.5, -5.0}}, {"center", {0.5, 0.5, 600.0}}, {"up", {0, 1, 0}}, {"fov_y", 0.01}}},
             {"tf", {{"points", {{0.0, 1, 1, 1, 0.0}, {1.0, 1, 1, 1, 0.0}}}}},  // clear: no ray turns opaque
             {"render", {{"step", 1e-3}, {"early_termination", 1.0}, {"space_skipping", false}}}};
  const json peak_tf = {
      {"points",
       {{0.0, 1, 1, 1, 0}, {0.499, 1, 1, 1, 0}, {0.5, 1, 1, 1, 0.001}, {0.501, 1, 1, 1, 0}, {1.0, 1, 1, 1, 0}}}};
  for (const auto& [vs, peaks] : {std::pair{0, false}, std::pair{7, false}, std::pair{0, true}, std::pair{3, true}}) {
    sj["render"]["virtual_samples"] = vs;
    sj["render"]["step"] = 1e-3;
    if (peaks) {
      sj["render"]["classification"] = "peaks";
      sj["tf"] = peak_tf;
    }
    render::RenderStats st;
    const Image g = test::render_gpu(gv, test::make_scene(*v, sj), render::RenderPath::Fragment, &st);
    EXPECT_TRUE(test::all_finite(g));
    ASSERT_GT(st.sample_cap, 1000) << "vs " << vs;
    EXPECT_LE(st.sample_cap, kMaxSamplesPerRay);
    EXPECT_EQ(st.rays_at_cap, 4) << "vs " << vs;
    EXPECT_EQ(st.samples_max, double(st.sample_cap + (vs ? 1 : 0))) << "vs " << vs;  // + the spline's closing one
    // Just under the cap: every lattice point of the ray, counted exactly.
    const double step = 1199.0 / (0.9 * st.sample_cap);
    sj["render"]["step"] = step;
    test::render_gpu(gv, test::make_scene(*v, sj), render::RenderPath::Fragment, &st);
    EXPECT_EQ(st.rays_at_cap, 0) << "vs " << vs;
    EXPECT_NEAR(st.samples_max, std::floor(1199.0 / step) + 1 + (vs ? 1 : 0), 1.0) << "vs " << vs;
  }
}

TEST(Differential, OrthographicIsUniformAtTheFootprint) {
  auto v = ml();
  test::TestVolume gv(v);
  const json cam = {{"eye", {20, 20, 120}},
                    {"center", {20, 20, 20}},
                    {"up", {0, 1, 0}},
                    {"projection", "orthographic"},
                    {"height", 60}};
  const ResolvedScene sd = test::make_scene(*v, scene_json(cam, {{"sampling", "differential"}, {"s_k", 3}}));
  const SamplingPlan plan = plan_sampling(sd);
  EXPECT_FALSE(plan.differential);
  EXPECT_NEAR(plan.step, 3 * std::hypot(60.0 / 64, 60.0 / 64), 1e-9);  // s_k x the pixel diagonal
  render::RenderStats st;
  const Image d = test::render_gpu(gv, sd, render::RenderPath::Fragment, &st);
  EXPECT_EQ(st.variant.find("+diff"), std::string::npos) << st.variant;
  const Image u =
      test::render_gpu(gv, test::make_scene(*v, scene_json(cam, {{"step", plan.step}})), render::RenderPath::Fragment);
  EXPECT_GE(reference::compare(d, u).psnr, 100.0);
}

// A constant volume: any step integrates it exactly (Beer-Lambert with the opacity corrected
// for the step taken), so adaptive sampling takes the largest multiplier everywhere and must
// give the uniform image with far fewer samples (1/8 inside a cell; each cell restarts at its
// first lattice index, so about 1/6 over a ray).
TEST(Adaptive, ConstantVolumeSameImageEighthOfTheSamples) {
  auto v = test::make_volume(GeneratorKind::Blobs, {48, 48, 48}, SourceType::U8);
  std::memset(v->data(), 100, size_t(v->voxel_count()));
  v->finalize_statistics();
  test::TestVolume gv(v);
  const json tf = {{"points", {{0, 0, 0, 0, 0}, {255, 1, 0.8, 0.5, 0.5}}}};
  json over = {{"image", {{"width", 64}, {"height", 64}}},
               {"tf", tf},
               {"camera", far_camera()},
               {"render", {{"step", 0.5}, {"early_termination", 1.0}}}};
  render::RenderStats su, sa;
  const Image u = test::render_gpu(gv, test::make_scene(*v, over), render::RenderPath::Fragment, &su);
  over["render"]["adaptive"] = true;
  const ResolvedScene sa_scene = test::make_scene(*v, over);
  const Image a = test::render_gpu(gv, sa_scene, render::RenderPath::Fragment, &sa);
  const auto e = reference::compare(a, u);
  std::printf("constant volume: uniform %.1f samples/ray, adaptive %.1f (%s); PSNR %.1f dB\n", su.samples_mean,
              sa.samples_mean, sa.variant.c_str(), e.psnr);
  EXPECT_NE(sa.variant.find("+adaptive"), std::string::npos);
  EXPECT_GE(e.psnr, 55.0);
  EXPECT_LT(sa.samples_mean, su.samples_mean / 4.0);
  EXPECT_GE(reference::compare(a, reference::render_reference(*v, sa_scene)).psnr, 55.0);
}

TEST(Adaptive, MultipliersFollowTheCellsDeviation) {
  auto v = ml();
  const MacrocellGrid cells = build_macrocells(*v);
  const double vs = volume_stddev(*v);
  ASSERT_GT(vs, 0);
  const auto m = adaptive_multipliers(cells, vs);
  for (size_t c = 0; c < cells.size(); ++c) {
    const double ratio = cells.stddev[c] / vs;
    const int want = ratio > 0 ? int(std::clamp(std::floor(2 / ratio + 1), 1.0, double(kMaxAdaptiveMultiplier)))
                               : kMaxAdaptiveMultiplier;
    ASSERT_EQ(int(m[c]), want) << c;
  }
  // Zero variance guarded: a constant volume gets the largest multiplier, not a division by 0.
  const auto flat = adaptive_multipliers(cells, 0.0);
  for (uint8_t x : flat) ASSERT_EQ(int(x), kMaxAdaptiveMultiplier);
}

TEST(Adaptive, GpuMatchesTheCpuTwinAndTheReference) {
  auto v = ml();
  test::TestVolume gv(v);
  for (const json& render :
       {json{{"adaptive", true}, {"step", 0.25}, {"space_skipping", false}}, json{{"adaptive", true}, {"step", 0.25}},
        json{{"adaptive", true}, {"sampling", "differential"}, {"s_k", 1}},
        // Segment methods: a run of occupied cells is walked as the reference
        // walks the ray, each cell from its first point with its multiplier.
        json{{"adaptive", true}, {"step", 0.5}, {"classification", "preint"}, {"space_skipping", false}},
        json{{"adaptive", true}, {"step", 1}, {"classification", "preint"}},
        json{{"adaptive", true}, {"step", 0.5}, {"classification", "peaks"}}}) {
    const ResolvedScene s = test::make_scene(*v, scene_json(far_camera(), render));
    render::RenderStats st;
    const Image g = test::render_gpu(gv, s, render::RenderPath::Fragment, &st);
    const Image c = reference::render_reference(*v, s);
    const auto e = reference::compare(g, c);
    std::printf("%-70s %-40s PSNR %.1f dB, samples/ray %.1f vs %.1f\n", render.dump().c_str(), st.variant.c_str(),
                e.psnr, mean_samples(g), mean_samples(c));
    EXPECT_GE(e.psnr, kMinTwinPsnr) << render.dump();
  }
}

}  // namespace
