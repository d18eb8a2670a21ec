// The GL ray caster against the CPU reference at the same step: scenes x
// filters x GPU paths, each with a measured PSNR bound; space skipping on/off identical.
#include <cmath>

#include <glm/geometric.hpp>

#include "core/volume_io.h"
#include "gpu/gpu_fixture.h"
#include "reference/reference_renderer.h"
#include "unit/test_util.h"

using namespace peakcast;
using nlohmann::json;

namespace {

// TF points given in [0, 1] of the volume's range, converted to data units.
json tf_over_range(const Volume& v, std::vector<std::array<double, 5>> pts) {
  json out = json::array();
  for (auto& p : pts) out.push_back({v.min_value + p[0] * (v.max_value - v.min_value), p[1], p[2], p[3], p[4]});
  return {{"points", out}};
}

struct SceneCase {
  std::string name;
  std::function<std::shared_ptr<Volume>()> volume;
  std::vector<std::array<double, 5>> tf;
  json camera;  // relative: eye offset in units of the box diagonal, from the box centre
};

json camera_for(const Volume& v, glm::dvec3 dir, glm::dvec3 up) {
  const glm::dvec3 c = v.origin + v.extent() * 0.5;
  const double r = glm::length(v.extent()) * 0.5;
  const glm::dvec3 eye = c + glm::normalize(dir) * (r / std::sin(15.0 * M_PI / 180.0));
  return {{"eye", {eye.x, eye.y, eye.z}}, {"center", {c.x, c.y, c.z}}, {"up", {up.x, up.y, up.z}}, {"fov_y", 30}};
}

const std::vector<std::array<double, 5>> kBands = {{0.0, 0, 0, 0, 0},           {0.3, 0.1, 0.3, 1.0, 0.0},
                                                   {0.45, 0.2, 0.6, 1.0, 0.15}, {0.55, 1.0, 0.7, 0.2, 0.6},
                                                   {0.7, 1.0, 1.0, 1.0, 0.0},   {1.0, 1, 1, 1, 0.0}};

std::vector<SceneCase> cases() {
  return {
      {"marschner_lobb_41",
       [] {
         return test::make_volume(GeneratorKind::MarschnerLobb, {41, 41, 41}, SourceType::F32);
       },
       kBands, nullptr},
      {"blobs_64_u8",
       [] {
         return test::make_volume(GeneratorKind::Blobs, {64, 64, 64}, SourceType::U8);
       },
       {{0.0, 0, 0, 0, 0}, {0.2, 0.9, 0.5, 0.2, 0.0}, {0.6, 0.9, 0.8, 0.6, 0.3}, {1.0, 1, 1, 1, 0.8}},
       nullptr},
      {"nucleon_real",
       [] { return std::make_shared<Volume>(load_volume(test::data_dir() / "nucleon.nhdr")); },
       {{0.0, 0, 0, 0, 0}, {0.1, 0.2, 0.4, 1.0, 0.0}, {0.4, 1.0, 0.8, 0.3, 0.2}, {1.0, 1, 1, 1, 0.9}},
       nullptr},
      {"headsq_real_int16_aniso",
       [] { return std::make_shared<Volume>(load_volume(test::data_dir() / "headsq/quarter.nhdr")); },
       {{0.0, 0, 0, 0, 0},
        {0.15, 0.8, 0.5, 0.4, 0.0},
        {0.3, 0.9, 0.7, 0.6, 0.05},
        {0.5, 1, 1, 1, 0.6},
        {1.0, 1, 1, 1, 0.9}},
       nullptr},
  };
}

struct Param {
  int scene;
  Filter filter;
  render::RenderPath path;
  bool shading;
};

void PrintTo(const Param& p, std::ostream* os) { *os << p.scene << "/" << to_string(p.filter); }

class GpuVsCpu : public ::testing::TestWithParam<Param> {};

// Measured on llvmpipe (Mesa 22.3.6): every case between 58 and 80 dB; the bound leaves room for
// other GPUs' filtering precision while staying far above what a broken method gives (< 30 dB).
constexpr double kMinPsnr = 50.0;

TEST_P(GpuVsCpu, SameStepMatchesTheReference) {
  const Param p = GetParam();
  const SceneCase sc = cases()[size_t(p.scene)];
  auto v = sc.volume();
  json over = {{"tf", tf_over_range(*v, sc.tf)},
               {"camera", camera_for(*v, {1.0, 0.7, 1.6}, {0, 1, 0})},
               {"render", {{"filter", to_string(p.filter)}, {"shading", p.shading}}}};
  ResolvedScene s = test::make_scene(*v, over);
  test::TestVolume gv(v);
  render::RenderStats st;
  Image g = test::render_gpu(gv, s, p.path, &st);
  Image c = reference::render_reference(*v, s);
  const auto e = reference::compare(g, c);
  std::printf("%-26s %-9s %-4s shade=%d: PSNR %.1f dB, max %.4f, samples/ray %.1f [%s]\n", sc.name.c_str(),
              to_string(p.filter), p.path == render::RenderPath::Compute ? "comp" : "frag", p.shading, e.psnr,
              e.max_abs, st.samples_mean, st.variant.c_str());
  EXPECT_GE(e.psnr, kMinPsnr);
  EXPECT_GT(st.samples_mean, 5.0);
  // The image is not trivially empty: some pixels are far from the background.
  double lit = 0;
  for (size_t i = 0; i < c.rgba.size(); i += 4) lit = std::max<double>(lit, c.rgba[i] + c.rgba[i + 1] + c.rgba[i + 2]);
  EXPECT_GT(lit, 0.3);
  if (e.psnr < kMinPsnr) test::save_artifacts(g, c, "gpu_vs_cpu");
}

std::vector<Param> params() {
  std::vector<Param> out;
  for (int s = 0; s < int(cases().size()); ++s)
    for (auto f : {Filter::Trilinear, Filter::Tricubic})
      for (auto path : {render::RenderPath::Fragment, render::RenderPath::Compute})
        out.push_back({s, f, path, s % 2 == 1});
  return out;
}

INSTANTIATE_TEST_SUITE_P(Scenes, GpuVsCpu, ::testing::ValuesIn(params()), [](const auto& info) {
  return cases()[size_t(info.param.scene)].name + "_" + to_string(info.param.filter) +
         (info.param.path == render::RenderPath::Compute ? "_compute" : "_fragment");
});

class Skipping : public ::testing::TestWithParam<int> {};

TEST_P(Skipping, OnAndOffAgreeWithin1Over255) {
  const SceneCase sc = cases()[size_t(GetParam())];
  auto v = sc.volume();
  test::TestVolume gv(v);
  for (auto filter : {Filter::Trilinear, Filter::Tricubic}) {
    json over = {{"tf", tf_over_range(*v, sc.tf)},
                 {"camera", camera_for(*v, {-0.4, 1.0, 0.8}, {0, 0, 1})},
                 {"render", {{"filter", to_string(filter)}, {"space_skipping", true}}}};
    ResolvedScene on = test::make_scene(*v, over);
    over["render"]["space_skipping"] = false;
    ResolvedScene off = test::make_scene(*v, over);
    render::RenderStats st_on, st_off;
    Image a = test::render_gpu(gv, on, render::RenderPath::Fragment, &st_on);
    Image b = test::render_gpu(gv, off, render::RenderPath::Fragment, &st_off);
    EXPECT_GT(st_on.empty_cells, 0) << "the TF must leave cells empty, or the test proves nothing";
    EXPECT_NE(st_on.variant, st_off.variant);
    const auto e = reference::compare(a, b);
    std::printf("%s %s: skipping max diff %.6f, samples/ray %.1f -> %.1f\n", sc.name.c_str(), to_string(filter),
                e.max_abs, st_off.samples_mean, st_on.samples_mean);
    EXPECT_LE(e.max_abs, 1.0 / 255.0);
    EXPECT_LT(st_on.samples_mean, st_off.samples_mean);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, Skipping, ::testing::Range(0, int(cases().size())),
                         [](const auto& info) { return cases()[size_t(info.param)].name; });

}  // namespace
