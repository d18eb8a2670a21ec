// Peak finding and preintegration on the GPU: against the CPU twin of the
// same algorithm, against the peak-model and DVR references, and the mode semantics.
#include <cmath>

#include <glm/geometric.hpp>

#include "core/volume_io.h"
#include "gpu/gpu_fixture.h"
#include "reference/reference_renderer.h"
#include "unit/test_util.h"

using namespace peakcast;
using nlohmann::json;

namespace {

// A Dirac-like peak of relative width `width` at relative value `at`, plus a smooth blue
// feature (Knoll Fig. 3), in the volume's data units.
json fig3_tf(const Volume& v, double at, double width, double blue_at = 0.3) {
  const double lo = v.min_value, span = v.max_value - v.min_value;
  auto x = [&](double r) { return lo + r * span; };
  return {{"points",
           {{x(0.0), 0.1, 0.3, 1.0, 0.0},
            {x(blue_at - 0.1), 0.2, 0.5, 1.0, 0.0},
            {x(blue_at), 0.2, 0.5, 1.0, 0.05},
            {x(blue_at + 0.1), 0.2, 0.5, 1.0, 0.0},
            {x(at - width), 1.0, 0.1, 0.0, 0.0},
            {x(at), 1.0, 0.1, 0.0, 0.8},
            {x(at + width), 1.0, 0.1, 0.0, 0.0},
            {x(1.0), 1.0, 1.0, 1.0, 0.0}}}};
}

json view_of(const Volume& v, glm::dvec3 dir, glm::dvec3 up = {0, 0, 1}) {
  const glm::dvec3 c = v.origin + v.extent() * 0.5;
  const double r = glm::length(v.extent()) * 0.5;
  const glm::dvec3 eye = c + glm::normalize(dir) * (r / std::sin(15.0 * M_PI / 180.0));
  return {{"eye", {eye.x, eye.y, eye.z}}, {"center", {c.x, c.y, c.z}}, {"up", {up.x, up.y, up.z}}, {"fov_y", 30}};
}

std::shared_ptr<Volume> heptane() {
  return std::make_shared<Volume>(load_volume(test::data_dir() / "heptane_151.nrrd"));
}
std::shared_ptr<Volume> marschner_lobb() {
  return test::make_volume(GeneratorKind::MarschnerLobb, {41, 41, 41}, SourceType::F32);
}

struct ModeCase {
  const char* classification;
  const char* mode;
  int max_peaks;
};
void PrintTo(const ModeCase& m, std::ostream* os) { *os << m.classification << "/" << m.mode; }

class SameAlgorithm : public ::testing::TestWithParam<ModeCase> {};

// The GL path and its CPU twin (same table, same regula falsi, double precision) agree.
TEST_P(SameAlgorithm, GpuMatchesTheCpuTwin) {
  const ModeCase m = GetParam();
  for (auto vol : {marschner_lobb(), heptane()}) {
    test::TestVolume gv(vol);
    for (const char* filter : {"trilinear", "tricubic"}) {
      ResolvedScene s = test::make_scene(*vol, {{"tf", fig3_tf(*vol, 0.62, 1e-4)},
                                                {"camera", view_of(*vol, {1.0, -0.8, 0.6})},
                                                {"image", {{"width", 80}, {"height", 64}}},
                                                {"render",
                                                 {{"classification", m.classification},
                                                  {"peak_mode", m.mode},
                                                  {"max_peaks", m.max_peaks},
                                                  {"filter", filter},
                                                  {"shading", true}}}});
      render::RenderStats st;
      Image g = test::render_gpu(gv, s, render::RenderPath::Fragment, &st);
      Image c = reference::render_reference(*vol, s);
      const auto e = reference::compare(g, c);
      std::printf("%-6s %-10s max%d %-9s %-22s PSNR %.1f dB, samples/ray %.1f [%s]\n", m.classification, m.mode,
                  m.max_peaks, filter, vol->name.c_str(), e.psnr, st.samples_mean, st.variant.c_str());
      ASSERT_TRUE(test::all_finite(g));
      // Measured on llvmpipe: 45-70 dB (a root that float places on the other side of a cell
      // face shades differently); a broken root solver or table lands below 30 dB.
      EXPECT_GE(e.psnr, 40.0) << vol->name << " " << filter;
      if (e.psnr < 40.0) test::save_artifacts(g, c, std::string(m.mode) + "_" + filter);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Modes, SameAlgorithm,
                         ::testing::Values(ModeCase{"peaks", "dvr+peaks", 4}, ModeCase{"peaks", "dvr+peaks", 1},
                                           ModeCase{"peaks", "xor", 4}, ModeCase{"peaks", "peaks_only", 4},
                                           ModeCase{"peaks", "dvr_only", 4}, ModeCase{"preint", "dvr+peaks", 4}),
                         [](const auto& info) {
                           std::string n = std::string(info.param.classification) + "_" + info.param.mode + "_" +
                                           std::to_string(info.param.max_peaks);
                           for (auto& ch : n)
                             if (ch == '+') ch = '_';
                           return n;
                         });

struct DiracCase {
  const char* volume;  // "heptane" or "marschner_lobb"
  int dims;            // Marschner-Lobb resolution
  double width;        // peak width, relative to the value range
  double min_psnr;     // measured on llvmpipe (see the note at the instantiation)
};
void PrintTo(const DiracCase& d, std::ostream* os) { *os << d.volume << d.dims << " " << d.width; }

class DiracPeak : public ::testing::TestWithParam<DiracCase> {};

// Knoll Fig. 3: a near-Dirac peak. Peak finding at a 1-voxel step reproduces the peak model;
// postclassification at the same step misses the peak.
TEST_P(DiracPeak, PeakFindingMatchesThePeakModelWherePostclassificationFails) {
  const DiracCase d = GetParam();
  auto vol = std::string(d.volume) == "heptane"
                 ? heptane()
                 : test::make_volume(GeneratorKind::MarschnerLobb, {d.dims, d.dims, d.dims}, SourceType::F32);
  test::TestVolume gv(vol);
  json over = {{"tf", fig3_tf(*vol, 0.62, d.width)},
               {"camera", view_of(*vol, {1.0, -0.8, 0.6})},
               {"image", {{"width", 96}, {"height", 80}}},
               {"render", {{"classification", "peaks"}, {"step", 1.0}, {"early_termination", 1.0}}}};
  ResolvedScene peaks = test::make_scene(*vol, over);
  over["render"]["classification"] = "post";
  ResolvedScene post = test::make_scene(*vol, over);
  auto ref = reference::render_converged(*vol, peaks, reference::OpticalModel::Peaks, 1e-4, 1.0 / 16.0);
  render::RenderStats st;
  Image pf = test::render_gpu(gv, peaks, render::RenderPath::Fragment, &st);
  Image pc = test::render_gpu(gv, post, render::RenderPath::Fragment);
  const auto e_pf = reference::compare(pf, ref.image), e_pc = reference::compare(pc, ref.image);
  std::printf(
      "%s width %.0e: reference step %.4f (change %.1e); peak finding %.1f dB (%.1f samples/ray), "
      "postclassification %.1f dB\n",
      d.volume, d.width, ref.step, ref.last_change, e_pf.psnr, st.samples_mean, e_pc.psnr);
  EXPECT_GE(e_pf.psnr, d.min_psnr);
  EXPECT_LE(e_pc.psnr, e_pf.psnr - 10.0) << "postclassification should miss the peak";
  if (e_pf.psnr < d.min_psnr) test::save_artifacts(pf, ref.image, "peaks_vs_model");
}

// Measured (llvmpipe, 96x80): ML 41^3 26.4 dB, ML 128^3 35.1 dB, heptane 34.5 dB; postclassification
// 15-19 dB. What peak finding misses at a 1-voxel step are segments that cross the peak value
// twice (sub-voxel slivers at silhouettes): the sign test sees no change. ML 41^3 is at the
// Nyquist limit, so they are common there; at 128^3 the same signal is resolved.
INSTANTIATE_TEST_SUITE_P(Volumes, DiracPeak,
                         ::testing::Values(DiracCase{"marschner_lobb", 41, 1e-4, 25.0},
                                           DiracCase{"marschner_lobb", 41, 1e-6, 25.0},
                                           DiracCase{"marschner_lobb", 128, 1e-6, 34.0},
                                           DiracCase{"heptane", 0, 1e-4, 33.0}, DiracCase{"heptane", 0, 1e-6, 33.0}),
                         [](const auto& info) {
                           return std::string(info.param.volume) +
                                  (info.param.dims ? std::to_string(info.param.dims) : std::string()) +
                                  (info.param.width > 1e-5 ? "_1em4" : "_1em6");
                         });

// Three opaque peaks inside one 8-voxel segment of a ramp: the first along the ray wins, so
// looking up the ramp shows the lowest value's colour and looking down it the highest's.
TEST(PeakOrder, SeveralPeaksInOneSegmentComeOutInRayOrder) {
  auto vol = test::make_volume(GeneratorKind::Ramp, {33, 9, 9}, SourceType::F32);
  test::TestVolume gv(vol);
  auto spike = [](double v, double r, double g, double b) {
    return std::vector<json>{{v - 1e-4, r, g, b, 0.0}, {v, r, g, b, 1.0}, {v + 1e-4, r, g, b, 0.0}};
  };
  json pts = json::array({{0.0, 0, 0, 0, 0}});
  for (auto& p : spike(0.40, 1, 0, 0)) pts.push_back(p);
  for (auto& p : spike(0.45, 0, 1, 0)) pts.push_back(p);
  for (auto& p : spike(0.50, 0, 0, 1)) pts.push_back(p);
  pts.push_back({1.0, 0, 0, 0, 0});
  for (int from : {-1, 1}) {
    const double ex = from < 0 ? -40.0 : 72.0;
    json over = {{"tf", {{"points", pts}}},
                 {"image", {{"width", 8}, {"height", 8}}},
                 {"camera",
                  {{"eye", {ex, 4, 4}},
                   {"center", {16, 4, 4}},
                   {"up", {0, 0, 1}},
                   {"projection", "orthographic"},
                   {"height", 6}}},
                 {"render", {{"classification", "peaks"}, {"step", 8.0}, {"peak_mode", "peaks_only"}}}};
    ResolvedScene s = test::make_scene(*vol, over);
    Image g = test::render_gpu(gv, s, render::RenderPath::Fragment);
    Image c = reference::render_reference(*vol, s);
    const float* px = g.pixel(4, 4);
    if (from < 0) {  // rising field along the ray: 0.40 (red) first
      EXPECT_GT(px[0], 0.9f);
      EXPECT_LT(px[2], 0.1f);
    } else {  // falling: 0.50 (blue) first
      EXPECT_GT(px[2], 0.9f);
      EXPECT_LT(px[0], 0.1f);
    }
    EXPECT_GE(reference::compare(g, c).psnr, 60.0);
  }
}

// A plateau of the field exactly at the peak value: both samples of a segment equal the isovalue.
TEST(PeakEdgeCases, NoNanWhenBothSamplesEqualTheIsovalue) {
  auto vol = test::float_volume({17, 9, 9}, [](int64_t i, int64_t, int64_t) {
    return i < 4 ? 0.0f : i > 12 ? 1.0f : 0.5f;
  });
  test::TestVolume gv(vol);
  json tf = {{"points",
              {{0.0, 0, 0, 0, 0},
               {0.5 - 1e-6, 1, 0, 0, 0},
               {0.5, 1, 0, 0, 0.7},
               {0.5 + 1e-6, 1, 0, 0, 0},
               {1.0, 0, 0, 0, 0}}}};
  for (const char* filter : {"trilinear", "tricubic"}) {
    ResolvedScene s = test::make_scene(
        *vol, {{"tf", tf},
               {"image", {{"width", 8}, {"height", 8}}},
               {"camera",
                {{"eye", {-30, 4, 4}},
                 {"center", {8, 4, 4}},
                 {"up", {0, 0, 1}},
                 {"projection", "orthographic"},
                 {"height", 6}}},
               {"render", {{"classification", "peaks"}, {"peak_mode", "peaks_only"}, {"filter", filter}}}});
    Image g = test::render_gpu(gv, s, render::RenderPath::Fragment);
    ASSERT_TRUE(test::all_finite(g));
    // The field rises 0 -> 0.5, stays at 0.5, rises to 1: one crossing of 0.5, one surface.
    EXPECT_NEAR(g.pixel(4, 4)[3], 0.7, 1e-5) << filter;
    EXPECT_NEAR(g.pixel(4, 4)[0], 0.7, 1e-5) << filter;
  }
}

TEST(PeakModes, PeaksOnlyAddsNoDvrAndDvrOnlyIsPostclassification) {
  auto vol = marschner_lobb();
  test::TestVolume gv(vol);
  // A rising opacity ramp (no local maximum: not a peak) with one spike on it.
  auto tf_with_ramp = [](double ramp) {
    return json{{"points",
                 {{0.0, 0.2, 0.5, 1.0, 0.0},
                  {0.62 - 1e-4, 0.2, 0.5, 1.0, 0.62 * ramp},
                  {0.62, 1.0, 0.1, 0.0, 0.8},
                  {0.62 + 1e-4, 0.2, 0.5, 1.0, 0.62 * ramp},
                  {1.0, 0.2, 0.5, 1.0, ramp}}}};
  };
  json over = {{"tf", tf_with_ramp(0.1)},
               {"camera", view_of(*vol, {1.0, -0.8, 0.6})},
               {"render", {{"classification", "peaks"}, {"peak_mode", "peaks_only"}}}};
  ResolvedScene only = test::make_scene(*vol, over);
  over["tf"] = tf_with_ramp(0.0);  // the same spike without the ramp
  ResolvedScene only_no_ramp = test::make_scene(*vol, over);
  Image a = test::render_gpu(gv, only, render::RenderPath::Fragment);
  Image b = test::render_gpu(gv, only_no_ramp, render::RenderPath::Fragment);
  EXPECT_EQ(reference::compare(a, b).max_abs, 0.0) << "peaks_only must ignore the DVR part of the TF";
  over["tf"] = tf_with_ramp(0.1);
  over["render"]["peak_mode"] = "dvr_only";
  ResolvedScene dvr_only = test::make_scene(*vol, over);
  over["render"] = {{"classification", "post"}};
  ResolvedScene post = test::make_scene(*vol, over);
  render::RenderStats st;
  Image c = test::render_gpu(gv, dvr_only, render::RenderPath::Fragment, &st);
  Image d = test::render_gpu(gv, post, render::RenderPath::Fragment);
  EXPECT_EQ(reference::compare(c, d).max_abs, 0.0);
  EXPECT_EQ(st.variant.find("peaks"), std::string::npos) << "dvr_only compiles no peak code";
  // dvr+peaks = postclassification plus the surfaces: the image gets more opaque (a faint ramp,
  // so that early termination does not saturate both).
  over["tf"] = tf_with_ramp(0.01);
  over["render"] = {{"classification", "post"}};
  d = test::render_gpu(gv, test::make_scene(*vol, over), render::RenderPath::Fragment);
  over["render"] = {{"classification", "peaks"}};
  Image e = test::render_gpu(gv, test::make_scene(*vol, over), render::RenderPath::Fragment);
  double alpha_post = 0, alpha_peaks = 0, alpha_only = 0;
  for (size_t i = 3; i < e.rgba.size(); i += 4) {
    alpha_post += d.rgba[i];
    alpha_peaks += e.rgba[i];
    alpha_only += a.rgba[i];
  }
  EXPECT_GT(alpha_peaks, alpha_post * 1.2);
  EXPECT_GT(alpha_only, 0.0);
}

// Preintegration on a smooth TF agrees with the converged DVR reference.
TEST(Preintegration, AgreesWithTheConvergedDvrReferenceOnASmoothTf) {
  // Measured on llvmpipe (80x64, step 2): Marschner-Lobb preintegration 34.4 dB, postclassification
  // 33.7 dB; heptane 41.8 and 40.0 dB. Bounds 1.5 dB below; preintegration must not lose to
  // postclassification on a smooth TF (a table built for the wrong step or range does).
  const struct {
    std::shared_ptr<const Volume> vol;
    double min_preint, min_post;
  } cases[] = {{marschner_lobb(), 32.9, 32.2}, {heptane(), 40.3, 38.5}};
  for (const auto& c : cases) {
    auto vol = c.vol;
    test::TestVolume gv(vol);
    const double lo = vol->min_value, span = vol->max_value - vol->min_value;
    json tf = {{"points",
                {{lo, 0.1, 0.2, 0.9, 0.0},
                 {lo + 0.35 * span, 0.2, 0.6, 0.9, 0.08},
                 {lo + 0.6 * span, 1.0, 0.6, 0.2, 0.25},
                 {lo + span, 1.0, 1.0, 1.0, 0.0}}}};
    json over = {{"tf", tf},
                 {"camera", view_of(*vol, {0.7, -1.0, 0.5})},
                 {"image", {{"width", 80}, {"height", 64}}},
                 {"render", {{"classification", "preint"}, {"step", 2.0}, {"early_termination", 1.0}}}};
    ResolvedScene pre = test::make_scene(*vol, over);
    over["render"]["classification"] = "post";
    ResolvedScene post = test::make_scene(*vol, over);
    auto ref = reference::render_converged(*vol, pre, reference::OpticalModel::Dvr, 1e-4, 1.0 / 16.0);
    Image a = test::render_gpu(gv, pre, render::RenderPath::Fragment);
    Image b = test::render_gpu(gv, post, render::RenderPath::Fragment);
    const auto ea = reference::compare(a, ref.image), eb = reference::compare(b, ref.image);
    std::printf("%s step 2: preintegration %.1f dB, postclassification %.1f dB vs converged DVR\n", vol->name.c_str(),
                ea.psnr, eb.psnr);
    EXPECT_GE(ea.psnr, c.min_preint) << vol->name;
    EXPECT_GE(eb.psnr, c.min_post) << vol->name;
    EXPECT_GE(ea.psnr, eb.psnr) << vol->name << ": preintegration should not lose to postclassification";
  }
}

}  // namespace

// Without shading the root's position is unused, so the ray casters count the secant steps
// regula falsi would take instead of taking them. The count, and every sample the
// traversal takes, must not change: shading alters colour only, so a shaded render of the same
// scene (which does solve every root) counts exactly the same samples and the same opacity.
TEST(PeakModes, UnshadedPeaksCountTheRootStepsTheyNoLongerTake) {
  for (auto vol : {marschner_lobb(), heptane()}) {
    test::TestVolume gv(vol);
    for (int secant : {0, 3, 5})
      for (const char* mode : {"dvr+peaks", "peaks_only"}) {
        json over = {{"tf", fig3_tf(*vol, 0.62, 1e-4)},
                     {"camera", view_of(*vol, {1.0, -0.8, 0.6})},
                     {"image", {{"width", 64}, {"height", 48}}},
                     {"render",
                      {{"classification", "peaks"},
                       {"peak_mode", mode},
                       {"secant_iterations", secant},
                       {"space_skipping", false}}}};
        render::RenderStats flat_st, shaded_st;
        Image flat = test::render_gpu(gv, test::make_scene(*vol, over), render::RenderPath::Fragment, &flat_st);
        over["render"]["shading"] = true;
        Image shaded = test::render_gpu(gv, test::make_scene(*vol, over), render::RenderPath::Fragment, &shaded_st);
        ASSERT_GT(flat_st.samples_total, 0.0);
        EXPECT_EQ(flat_st.samples_total, shaded_st.samples_total) << vol->name << " " << mode << " secant " << secant;
        double alpha_diff = 0;
        for (int y = 0; y < flat.height; ++y)
          for (int x = 0; x < flat.width; ++x)
            alpha_diff = std::max(alpha_diff, double(std::abs(flat.pixel(x, y)[3] - shaded.pixel(x, y)[3])));
        EXPECT_EQ(alpha_diff, 0.0) << vol->name << " " << mode;
      }
  }
}
