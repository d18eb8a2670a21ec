// Virtual samples (Lee et al. 2010): the GL ray caster against its CPU twin, tricubic
// step 1 + virtual samples against step 1/4, the Catmull-Rom window's reach, and space
// skipping with Lee's widened cell ranges (Fig. 14).
#include <algorithm>
#include <cmath>

#include "core/sampling.h"
#include "gpu/sampling_scenes.h"

using namespace peakcast;
using namespace peakcast::sampling_scenes;
using nlohmann::json;

namespace {

// Virtual samples (Lee et al. 2010): the shader against its CPU twin at the same settings.
TEST(VirtualSamples, GpuMatchesTheCpuTwin) {
  auto v = ml();
  test::TestVolume gv(v);
  const std::vector<Twin> twins = {
      {"far vs3 trilinear", far_camera(), {{"virtual_samples", 3}, {"step", 1.0}}},
      {"close vs7 tricubic", close_camera(), {{"virtual_samples", 7}, {"step", 1.0}, {"filter", "tricubic"}}},
      {"far vs3 peaks", far_camera(), {{"virtual_samples", 3}, {"step", 1.0}, {"classification", "peaks"}}},
      {"far vs3 preint", far_camera(), {{"virtual_samples", 3}, {"step", 1.0}, {"classification", "preint"}}},
      {"far vs3 shading, no skipping",
       far_camera(),
       {{"virtual_samples", 3}, {"step", 1.0}, {"shading", true}, {"space_skipping", false}}},
      {"close vs3 differential", close_camera(), {{"virtual_samples", 3}, {"sampling", "differential"}, {"s_k", 1}}},
  };
  check_twins(*v, gv, twins, "+vs");
}

// Lee Table 1 style: tricubic at step 1 with 3 virtual samples against tricubic at step 1/4
// (the same number of composited samples, a quarter of the filter evaluations).
TEST(VirtualSamples, StepOnePlusThreeAgainstStepQuarter) {
  auto v = ml();
  test::TestVolume gv(v);
  const ResolvedScene s1 = test::make_scene(*v, scene_json(far_camera(), {{"filter", "tricubic"}, {"step", 1.0}}, 96));
  const auto conv = reference::render_converged(*v, s1, reference::OpticalModel::Dvr, 1e-4);
  ASSERT_TRUE(conv.converged);
  struct Row {
    const char* name;
    json render;
    double psnr = 0, ms = 0, spr = 0;
    Image img = {};
  };
  std::vector<Row> rows = {{"tricubic x1", {{"filter", "tricubic"}, {"step", 1.0}}},
                           {"tricubic x4", {{"filter", "tricubic"}, {"step", 0.25}}},
                           {"tricubic x1 + vs3", {{"filter", "tricubic"}, {"step", 1.0}, {"virtual_samples", 3}}},
                           {"tricubic x1 + vs7", {{"filter", "tricubic"}, {"step", 1.0}, {"virtual_samples", 7}}}};
  for (auto& row : rows) {
    const ResolvedScene s = test::make_scene(*v, scene_json(far_camera(), row.render, 96));
    render::RenderStats st;
    std::vector<double> ms;
    for (int f = 0; f < 4; ++f) {
      row.img = test::render_gpu(gv, s, render::RenderPath::Fragment, &st);
      if (f) ms.push_back(st.render_ms);
    }
    std::sort(ms.begin(), ms.end());
    row.ms = ms[ms.size() / 2];
    row.spr = st.samples_mean;
    row.psnr = reference::compare(row.img, conv.image).psnr;
    std::printf("%-20s %8.2f ms %7.1f filter evaluations/ray  PSNR vs converged %.2f dB\n", row.name, row.ms, row.spr,
                row.psnr);
  }
  std::printf("x1 + vs3 against x4: PSNR %.2f dB, time ratio %.2f\n", reference::compare(rows[2].img, rows[1].img).psnr,
              rows[1].ms / rows[2].ms);
  // The true samples are those of step 1 (plus the one past the exit that closes the spline):
  // about a quarter of step 1/4's filter evaluations.
  EXPECT_NEAR(rows[2].spr, rows[0].spr + 1, 0.02 * rows[0].spr);
  EXPECT_LT(rows[2].spr, 0.3 * rows[1].spr);
  // Measured on llvmpipe: x1 42.2 dB, x4 54.0, x1 + vs3 53.8, x1 + vs7 59.4; x1 + vs3 against
  // x4 70.6 dB (Lee: visually identical). Bounds well below, far above what x1 alone reaches.
  EXPECT_GT(rows[2].psnr, rows[0].psnr + 8.0);
  EXPECT_GT(rows[3].psnr, rows[0].psnr + 8.0);
  EXPECT_GT(reference::compare(rows[2].img, rows[1].img).psnr, 60.0);
}

// The Catmull-Rom window reaches two steps either side; longest_step bounds every step of every
// ray (checked over all pixels of a differential close-up), and the ring follows from it.
TEST(VirtualSamples, WindowReachBoundsEveryStep) {
  auto v = ml();  // 41^3, spacing 1, 8-voxel cells
  for (const auto& [render, ring] :
       {std::pair{json{{"step", 2.0}}, 1}, std::pair{json{{"step", 8.0}}, 2}, std::pair{json{{"step", 12.0}}, 3},
        std::pair{json{{"step", 13.0}}, -1}, std::pair{json{{"step", 1.0}, {"adaptive", true}}, 2},
        std::pair{json{{"step", 2.0}, {"adaptive", true}}, -1}}) {
    const ResolvedScene s = test::make_scene(*v, scene_json(far_camera(), render));
    EXPECT_EQ(virtual_sample_ring(plan_sampling(s), s, 8), ring) << render.dump();
  }
  for (double sk : {0.5, 4.0, 64.0}) {
    const ResolvedScene s =
        test::make_scene(*v, scene_json(close_camera(), {{"sampling", "differential"}, {"s_k", sk}}));
    const SamplingPlan plan = plan_sampling(s);
    const double bound = longest_step(plan, s);
    const ViewSetup view = setup_view(s.camera, (s.box_min + s.box_max) * 0.5, s.scene.width, s.scene.height);
    double longest = 0.0;
    for (int y = 0; y < s.scene.height; ++y)
      for (int x = 0; x < s.scene.width; ++x) {
        const Ray r = make_ray(view, x, y);
        double t0, t1;
        if (!intersect_box(r, (s.box_max - s.box_min) * 0.5, t0, t1)) continue;
        const RayLattice l = ray_lattice(plan, view, r, t0);
        longest = std::max(longest, l.step(std::floor(l.index_at(t1)), 1));  // the last, longest
      }
    EXPECT_GT(longest, 0.0);
    EXPECT_LE(longest, bound) << "s_k " << sk;
    EXPECT_GT(longest, 0.5 * bound) << "s_k " << sk << ": the bound should not be loose";
  }
}

// Slabs 4 voxels thick across x on zero, at 0.8 except a band at 0.9 (16 <= y < 32), and one
// voxel at 1 far from them (the value range): sampled at step 2 across the slabs, the true
// samples of the 0.8 parts never exceed 0.8, but the Catmull-Rom segment between two 0.8
// samples overshoots to ~0.85.
std::shared_ptr<Volume> slabs() {
  return test::float_volume({48, 48, 48}, [](int64_t i, int64_t j, int64_t k) {
    if (i == 47 && j == 47 && k == 47) return 1.0f;
    const bool slab = j >= 8 && j < 40 && k >= 8 && k < 40 && (i % 12) >= 4 && (i % 12) < 8 && i < 40;
    return slab ? (j / 16 == 1 ? 0.9f : 0.8f) : 0.0f;
  });
}

// Lee Fig. 14: a Catmull-Rom segment overshoots its true samples, so a cell whose values all
// lie below a TF's visible band can still hold visible virtual samples. Skipping cells by their
// raw range loses them in cell-shaped patches ("streaks"); widening each range by (M - m)/8
// over the cells the spline's window reaches keeps every such cell, and skipping then changes
// nothing at all (the skipping traversal visits the same samples, in the same windows).
TEST(VirtualSamples, WideningKeepsTheCellsSkippingWouldStreak) {
  auto v = slabs();
  test::TestVolume gv(v);
  auto& caster = *test::gpu().caster;
  const json camera = {{"eye", {-60, 30, 20}}, {"center", {24, 24, 24}}, {"up", {0, 1, 0}}, {"fov_y", 40}};
  json sj = scene_json(camera, {{"virtual_samples", 7}, {"step", 2.0}}, 96);
  sj["tf"] = {{"points", {{0.0, 0, 0, 0, 0}, {0.81, 1, 0.6, 0.2, 0.0}, {0.82, 1, 0.6, 0.2, 0.3}, {1.0, 1, 1, 1, 0.3}}}};
  auto render = [&](bool skipping, double widening, render::RenderStats* st = nullptr) {
    sj["render"]["space_skipping"] = skipping;
    test::gpu().switches->set_virtual_sample_widening(widening);
    Image img = test::render_gpu(gv, test::make_scene(*v, sj), render::RenderPath::Fragment, st);
    test::gpu().switches->set_virtual_sample_widening(kCatmullRomOvershoot);
    return img;
  };
  auto differing = [](const Image& a, const Image& b) {
    int n = 0;
    for (size_t i = 0; i < a.rgba.size(); i += 4)
      n += std::max({std::abs(a.rgba[i] - b.rgba[i]), std::abs(a.rgba[i + 1] - b.rgba[i + 1]),
                     std::abs(a.rgba[i + 2] - b.rgba[i + 2])}) > 2.0f / 255.0f;
    return n;
  };
  render::RenderStats st_raw, st_wide;
  const Image dense = render(false, kCatmullRomOvershoot);
  const Image raw = render(true, 0.0, &st_raw);
  const Image wide = render(true, kCatmullRomOvershoot, &st_wide);
  EXPECT_NE(st_raw.variant.find("+skip"), std::string::npos) << st_raw.variant;
  EXPECT_NE(st_wide.variant.find("+skip"), std::string::npos) << st_wide.variant;
  EXPECT_GT(st_raw.empty_cells, st_wide.empty_cells);  // the widening keeps cells
  EXPECT_GT(st_wide.empty_cells, 0);                   // and skipping still skips
  const int visible = differing(dense, Image(dense.width, dense.height));
  const int streaks = differing(raw, dense), kept = differing(wide, dense);
  std::printf(
      "empty cells raw %lld widened %lld; pixels showing the slabs %d; off by > 2/255: raw %d, widened %d; "
      "PSNR raw %.1f dB, widened %.1f dB\n",
      (long long)st_raw.empty_cells, (long long)st_wide.empty_cells, visible, streaks, kept,
      reference::compare(raw, dense).psnr, reference::compare(wide, dense).psnr);
  test::save_artifacts(raw, dense, "streaks");  // look at them: build/test-artifacts/
  EXPECT_GT(visible, 1000);
  EXPECT_GT(streaks, visible / 4);  // the 0.8 parts, seen through the overshoot only, are lost
  EXPECT_LT(streaks, visible);      // the 0.9 band, visible in its true samples, is not
  EXPECT_EQ(kept, 0);
  EXPECT_GE(reference::compare(wide, dense).psnr, 100.0);
  // The CPU twin never skips: the widened, skipping GPU image matches it too.
  EXPECT_GE(reference::compare(wide, reference::render_reference(*v, test::make_scene(*v, sj))).psnr, kMinTwinPsnr);
}

}  // namespace
