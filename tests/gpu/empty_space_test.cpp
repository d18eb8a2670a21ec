// Empty-space leaps: the shared traversal (shaders/ray/walks.glsl) leaps across the cube of empty macrocells the
// empty-space distance promises instead of stepping through them one by one, and is driven by
// the lattice (an iteration per sample or leap) rather than by the cells crossed. A leap must skip
// exactly the lattice points the steps skip: the same pixels and the same samples per ray, over
// sparse volumes, oblique, axis-parallel, inside-the-box and orthographic views, and the
// methods that join samples into segments (peak finding, preintegration).
#include <cmath>
#include <tuple>
#include <utility>

#include "core/occupancy.h"
#include "cpu/cpu_renderer.h"
#include "encode/png.h"
#include "gpu/gpu_fixture.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

struct LeapCase {
  const char* name;
  GeneratorKind kind;
  Dims dims;
  json tf;      // over [0, 1] of the value range
  json camera;  // eye, center, up (+ projection)
  json render;
};

void PrintTo(const LeapCase& c, std::ostream* os) { *os << c.name; }

json tf_points(const Volume& v, const json& pts) {
  json out = json::array();
  for (const auto& p : pts)
    out.push_back({v.min_value + p[0].get<double>() * (v.max_value - v.min_value), p[1], p[2], p[3], p[4]});
  return {{"points", out}};
}

const json kCore = {{0.0, 0, 0, 0, 0}, {0.72, 0, 0, 0, 0}, {0.8, 1.0, 0.6, 0.2, 0.6}, {1.0, 1, 1, 1, 0.9}};
const json kPeak = {
    {0.0, 0, 0, 0, 0}, {0.7 - 1e-4, 0, 0, 0, 0}, {0.7, 1, 0.3, 0.1, 0.9}, {0.7 + 1e-4, 0, 0, 0, 0}, {1.0, 0, 0, 0, 0}};

const LeapCase kCases[] = {
    {"blobs_oblique",
     GeneratorKind::Blobs,
     {128, 128, 128},
     kCore,
     {{"eye", {300, 240, 380}}, {"center", {64, 64, 64}}, {"up", {0, 1, 0}}},
     {}},
    {"blobs_axis_parallel",
     GeneratorKind::Blobs,
     {128, 128, 128},
     kCore,
     {{"eye", {63.5, 63.5, 500}}, {"center", {63.5, 63.5, 63.5}}, {"up", {0, 1, 0}}},
     {}},
    {"blobs_eye_inside",
     GeneratorKind::Blobs,
     {128, 128, 128},
     kCore,
     {{"eye", {20, 30, 100}}, {"center", {70, 64, 40}}, {"up", {0, 1, 0}}, {"fov_y", 60}},
     {}},
    {"sphere_ortho",
     GeneratorKind::Sphere,
     {96, 80, 112},
     kCore,
     {{"eye", {200, 150, 250}},
      {"center", {48, 40, 56}},
      {"up", {0, 1, 0}},
      {"projection", "orthographic"},
      {"height", 150}},
     {}},
    {"vessels_tricubic",
     GeneratorKind::Vessels,
     {96, 96, 96},
     kCore,
     {{"eye", {-150, 200, 260}}, {"center", {48, 48, 48}}, {"up", {0, 1, 0}}},
     {{"filter", "tricubic"}}},
    {"blobs_peaks",
     GeneratorKind::Blobs,
     {128, 128, 128},
     kPeak,
     {{"eye", {300, -200, 380}}, {"center", {64, 64, 64}}, {"up", {0, 1, 0}}},
     {{"classification", "peaks"}}},
    {"blobs_preint",
     GeneratorKind::Blobs,
     {128, 128, 128},
     kCore,
     {{"eye", {-260, 240, -300}}, {"center", {64, 64, 64}}, {"up", {0, 1, 0}}},
     {{"classification", "preint"}}},
};

class Leaps : public ::testing::TestWithParam<LeapCase> {};

// Both traversals that skip space, each leaping by the empty-space distance and stepping through
// every empty cell one at a time (leaps off): the lattice-driven loop (what space skipping renders
// with) and the 3D-DDA (adaptive sampling's). The leaps must visit exactly the points the steps do.
TEST_P(Leaps, SkipExactlyWhatSteppingThroughEmptyCellsSkips) {
  const LeapCase& c = GetParam();
  auto v = test::make_volume(c.kind, c.dims, default_type(c.kind));
  test::TestVolume gv(v);
  for (const bool adaptive : {false, true}) {
    json render = c.render;
    if (adaptive) render["adaptive"] = true;
    json j = {{"image", {{"width", 96}, {"height", 96}}},
              {"tf", tf_points(*v, c.tf)},
              {"camera", c.camera},
              {"render", render}};
    const ResolvedScene s = test::make_scene(*v, j);
    // The scene must leave room to leap: some cell at least two cells from anything visible.
    const MacrocellGrid& cells = gv.macrocells(s.scene.render.filter);
    const Occupancy occ = classify_cells(cells, s.tf, gv.tf_lo(), gv.tf_hi());
    ASSERT_GT(*std::max_element(occ.distance.begin(), occ.distance.end()), 2) << "nothing to leap over";
    render::RenderStats st_leap, st_step;
    const Image leap = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_leap);
    test::gpu().switches->set_empty_space_leaps(false);
    const Image step = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_step);
    test::gpu().switches->set_empty_space_leaps(true);
    SCOPED_TRACE(st_leap.variant);
    ASSERT_NE(st_leap.variant.find("+skip"), std::string::npos);
    ASSERT_EQ(st_leap.variant.find("+adaptive") != std::string::npos, adaptive);
    EXPECT_GT(st_step.samples_mean, 0.0) << "nothing visible: the test would prove nothing";
    const auto e = reference::compare(leap, step);
    const size_t differ = size_t(std::count_if(leap.samples.begin(), leap.samples.end(),
                                               [&, i = size_t(0)](float x) mutable { return x != step.samples[i++]; }));
    std::printf("%-20s %-36s max diff %.2e, samples/ray %.4f (steps %.4f), samples differ on %zu rays\n", c.name,
                st_leap.variant.c_str(), e.max_abs, st_leap.samples_mean, st_step.samples_mean, differ);
    EXPECT_EQ(leap.rgba, step.rgba);
    EXPECT_EQ(differ, 0u);
    if (e.max_abs > 0) test::save_artifacts(leap, step, std::string(c.name) + (adaptive ? "_dda" : "_lattice"));
  }
}

// The CPU backend takes the leaps up to each ray's first occupied cell for 16 rays at once in
// SIMD lanes (cpu::cast_rays): bit for bit what each ray alone does, pixels and sample counts.
TEST_P(Leaps, CpuRayPacketsEqualSingleRays) {
  auto* cpu = test::gpu().cpu;
  if (!cpu) GTEST_SKIP() << "CPU backend only";
  const LeapCase& c = GetParam();
  auto v = test::make_volume(c.kind, c.dims, default_type(c.kind));
  test::TestVolume gv(v);
  json j = {{"image", {{"width", 93}, {"height", 77}}},
            {"tf", tf_points(*v, c.tf)},
            {"camera", c.camera},
            {"render", c.render}};
  const ResolvedScene s = test::make_scene(*v, j);
  render::RenderStats st_packets, st_single;
  const Image packets = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_packets);
  cpu->set_ray_packets(false);
  const Image single = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_single);
  cpu->set_ray_packets(true);
  ASSERT_NE(st_packets.variant.find("+skip"), std::string::npos) << st_packets.variant;
  EXPECT_GT(st_single.samples_mean, 0.0) << "nothing visible: the test would prove nothing";
  EXPECT_EQ(packets.rgba, single.rgba);
  EXPECT_EQ(packets.samples, single.samples);
}

// The CPU backend walks runs of occupied points of plain DVR (post or preintegrated, uniform
// steps) through its dense_run fast path instead of the shared visit: bit for bit what the shared
// walks give without it, pixels and sample counts, with space skipping (the runs between leaps)
// and without (one run along the whole ray), with the default early termination (the fast
// path's stop), and with a ray texture whose step multiplier varies over the image (the fast
// path's opacity corrected on every sample, its early termination per ray). blobs_peaks does not
// take the fast path (peaks).
TEST_P(Leaps, CpuDenseRunsEqualTheSharedWalks) {
  auto* cpu = test::gpu().cpu;
  if (!cpu) GTEST_SKIP() << "CPU backend only";
  const LeapCase& c = GetParam();
  auto v = test::make_volume(c.kind, c.dims, default_type(c.kind));
  test::TestVolume gv(v);
  for (const auto& [skip, ray_texture] : {std::pair{true, false}, {false, false}, {true, true}}) {
    json render = c.render;
    render["sampling"] = "uniform";  // (the fast path takes uniform steps, unshaded)
    render["shading"] = false;
    render["space_skipping"] = skip;
    if (ray_texture) {  // a finer step in a soft disk, a coarser one and an earlier stop elsewhere
      render["ray_texture"] = {
          {"mapping", "view"},
          {"size", {64, 64}},
          {"strokes",
           {{{"channel", "step"}, {"center", {0.5, 0.5}}, {"radius", 1.0}, {"value", 1.7}},
            {{"channel", "step"}, {"center", {0.45, 0.55}}, {"radius", 0.3}, {"falloff", 0.8}, {"value", 0.4}},
            {{"channel", "termination"}, {"center", {0.7, 0.3}}, {"radius", 0.25}, {"falloff", 0.5}, {"value", 0.6}}}}};
    }
    json j = {{"image", {{"width", 61}, {"height", 53}}},
              {"tf", tf_points(*v, c.tf)},
              {"camera", c.camera},
              {"render", render}};
    const ResolvedScene s = test::make_scene(*v, j);
    render::RenderStats st_dense, st_shared;
    const Image dense = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_dense);
    cpu->set_dense_runs(false);
    const Image shared = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_shared);
    cpu->set_dense_runs(true);
    SCOPED_TRACE(st_dense.variant);
    EXPECT_EQ(st_dense.variant.find("+skip") != std::string::npos, skip);
    EXPECT_EQ(st_dense.variant.find("+raytex") != std::string::npos, ray_texture);
    EXPECT_GT(st_shared.samples_mean, 0.0) << "nothing visible: the test would prove nothing";
    EXPECT_EQ(dense.rgba, shared.rgba);
    EXPECT_EQ(dense.samples, shared.samples);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, Leaps, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<LeapCase>& i) { return std::string(i.param.name); });

// A frame with nothing visible: when no cell is occupied, the CPU backend fills the
// background without casting a ray. Every method must still give exactly the background, and
// the float output (which reads the sample counts) the same pixels.
TEST(NothingVisible, EveryMethodGivesExactlyTheBackground) {
  auto vol = test::make_volume(GeneratorKind::Blobs, {40, 36, 32}, SourceType::U8);
  test::TestVolume gv(vol);
  const double lo = vol->min_value, hi = vol->max_value;
  // Opacity zero everywhere; the peak-finding scene's peak lies beyond the data's range.
  const json zero = {{"points", {{lo, 1, 0.5, 0.2, 0.0}, {hi, 0.2, 0.5, 1, 0.0}}}};
  const json beyond = {
      {"points", {{lo, 0, 0, 0, 0}, {hi + 10, 0, 0, 0, 0}, {hi + 11, 1, 0, 0, 0.9}, {hi + 12, 0, 0, 0, 0}}}};
  const std::vector<json> renders = {
      {{"classification", "post"}},
      {{"classification", "preint"}},
      {{"classification", "peaks"}, {"shading", true}},
      {{"filter", "tricubic"}, {"virtual_samples", 3}},
      {{"adaptive", true}},
  };
  for (const json& r : renders) {
    const json tf = r.value("classification", "") == "peaks" ? beyond : zero;
    ResolvedScene s = test::make_scene(
        *vol, {{"tf", tf}, {"render", r}, {"background", {0.1, 0.4, 0.7}}, {"image", {{"width", 61}, {"height", 47}}}});
    render::RenderRequest req;
    req.output = render::RenderOutput::Rgb8;
    render::RenderStats st8;
    const render::Rgb8Image img = test::gpu().caster->render(gv, s, req, &st8).rgb8;
    if (!test::gpu().gl) {  // the CPU backend took the shortcut: no ray was cast
      EXPECT_NE(st8.variant.find("+nothing-visible"), std::string::npos) << r.dump() << " " << st8.variant;
    }
    const uint8_t want[3] = {26, 102, 179};  // round(255 * background)
    size_t off = 0;
    for (size_t p = 0; p < img.rgb.size(); ++p) off += img.rgb[p] != want[p % 3];
    EXPECT_EQ(off, 0u) << r.dump();
    render::RenderStats st;
    req.output = render::RenderOutput::Float;
    const Image f = test::gpu().caster->render(gv, s, req, &st).image;
    EXPECT_EQ(encode::to_rgb8(f), img.rgb) << r.dump();
    EXPECT_EQ(st.samples_total, 0.0) << r.dump();
    EXPECT_GT(st.rays_hit, 0) << r.dump();
  }
}

}  // namespace
}  // namespace peakcast
