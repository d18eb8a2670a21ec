// A scene's first picture: the TF derived from the histogram, the three-quarter default view,
// and the warning for peak finding with a TF that has no peak.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "core/auto_tf.h"
#include "core/generators.h"
#include "core/peaks.h"
#include "core/scene.h"

using namespace peakcast;

namespace {

// Two classes: `n0` voxels around bin 100, `n1` around bin 700 (of 1024 over [0, 1023]).
std::vector<uint64_t> bimodal(uint64_t n0, uint64_t n1) {
  std::vector<uint64_t> h(1024, 0);
  for (int d = -20; d <= 20; ++d) {
    h[100 + d] = n0 / 41;
    h[700 + d] = n1 / 41;
  }
  return h;
}

bool has_warning(const ResolvedScene& r, const std::string& part) {
  for (const auto& w : r.warnings)
    if (w.find(part) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST(AutoTf, OtsuSplitsTwoClassesBetweenThem) {
  for (auto [n0, n1] : {std::pair<uint64_t, uint64_t>{41000, 41000}, {410000, 4100}, {4100, 410000}}) {
    const double t = otsu_threshold(bimodal(n0, n1), 0.0, 1024.0);
    EXPECT_GT(t, 120.0) << n0 << " " << n1;
    EXPECT_LT(t, 680.0) << n0 << " " << n1;
  }
  EXPECT_EQ(otsu_threshold({}, 3.0, 5.0), 3.0);
  EXPECT_EQ(otsu_threshold(std::vector<uint64_t>(1024, 0), 3.0, 5.0), 3.0);
}

TEST(AutoTf, TransparentBelowTheSplitRisingThroughViridisAbove) {
  const auto h = bimodal(410000, 41000);  // much background, some structure
  AutoTfInput in;
  in.histogram = &h;
  in.lo = 0;
  in.hi = 1024;
  in.ray_length = 200;
  const TransferFunction tf = derive_transfer_function(in);
  const double t = otsu_threshold(h, 0, 1024);
  EXPECT_EQ(tf.eval(100).a, 0.0);  // the background class
  EXPECT_EQ(tf.eval(t).a, 0.0);
  double last = 0;
  for (double v = t; v <= 1024; v += 8) {  // opacity never falls: no peak, plain DVR
    EXPECT_GE(tf.eval(v).a, last);
    last = tf.eval(v).a;
  }
  EXPECT_GT(tf.eval(720).a, 0.0);
  EXPECT_LE(tf.eval(1024).a, 0.8);
  EXPECT_TRUE(find_peaks(tf).empty());
  // viridis: dark blue-violet at the low end, yellow at the top.
  const glm::dvec4 top = tf.eval(1024);
  EXPECT_GT(top.r, 0.9);
  EXPECT_GT(top.g, 0.85);
  EXPECT_LT(top.b, 0.2);
}

TEST(AutoTf, OpacityScalesWithHowMuchStructureARayCrosses) {
  const auto sparse = bimodal(410000, 4100), dense = bimodal(4100, 410000);
  AutoTfInput in;
  in.lo = 0;
  in.hi = 1024;
  in.ray_length = 200;
  in.histogram = &sparse;
  const double a_sparse = derive_transfer_function(in).eval(1024).a;
  in.histogram = &dense;
  const double a_dense = derive_transfer_function(in).eval(1024).a;
  in.ray_length = 2000;
  const double a_dense_long = derive_transfer_function(in).eval(1024).a;
  EXPECT_GT(a_sparse, a_dense);      // little structure: more opaque, or nothing shows
  EXPECT_GT(a_dense, a_dense_long);  // long rays: less opaque, or only the first voxels show
}

TEST(AutoTf, PeakClassificationGetsAPeakAtTheSplit) {
  const auto h = bimodal(41000, 41000);
  AutoTfInput in;
  in.histogram = &h;
  in.lo = 0;
  in.hi = 1024;
  in.with_peak = true;
  const TransferFunction tf = derive_transfer_function(in);
  const auto peaks = find_peaks(tf);
  ASSERT_EQ(peaks.size(), 1u);
  EXPECT_NEAR(peaks[0].value, otsu_threshold(h, 0, 1024), 1e-9);
  EXPECT_GT(peaks[0].rgba.a, 0.5);
}

TEST(AutoTf, NoHistogramGivesARampOverTheRange) {
  AutoTfInput in;
  in.lo = 2;
  in.hi = 6;
  const TransferFunction tf = derive_transfer_function(in);
  EXPECT_EQ(tf.eval(2).a, 0.0);
  EXPECT_GT(tf.eval(6).a, 0.0);
  in.hi = 2;  // a constant volume
  EXPECT_NO_THROW(derive_transfer_function(in));
}

TEST(AutoTf, FacesAboveTheSplitMirrorTheRamp) {
  const auto h = bimodal(41000, 410000);  // the upper class the larger, as a distance field's outside
  AutoTfInput in;
  in.histogram = &h;
  in.lo = 0;
  in.hi = 1024;
  in.ray_length = 200;
  const double t = otsu_threshold(h, 0, 1024);
  std::vector<uint64_t> border(1024, 0);
  border[700] = 80;  // faces: 80% above the split
  border[100] = 20;
  in.border_histogram = &border;
  const TransferFunction tf = derive_transfer_function(in);
  for (double v = 680; v <= 1024; v += 4) EXPECT_EQ(tf.eval(v).a, 0.0) << v;  // the background class
  EXPECT_GT(tf.eval(100).a, 0.0);                                             // the structure below
  double last = 0;
  for (double v = 680; v >= 0; v -= 8) {  // rising as the value falls
    EXPECT_GE(tf.eval(v).a, last);
    last = tf.eval(v).a;
  }
  border[700] = 70;  // below kBackgroundAbove: the usual ramp
  border[100] = 30;
  const TransferFunction up = derive_transfer_function(in);
  EXPECT_EQ(up.eval(100).a, 0.0);
  EXPECT_GT(up.eval(720).a, 0.0);
  in.with_peak = true;  // a peak at the mirrored split
  border[700] = 90;
  border[100] = 10;
  const auto peaks = find_peaks(derive_transfer_function(in));
  ASSERT_EQ(peaks.size(), 1u);  // between the classes, at the background's edge
  EXPECT_GT(peaks[0].value, t);
  EXPECT_LE(peaks[0].value, 680.0);
}

// A float signed distance field of a sphere (negative inside): the faces are all background, at
// the top of the range, so the derived TF draws the sphere, not the box around it.
TEST(FirstView, ADistanceFieldDrawsItsInside) {
  VolumeHeader head;
  head.dims = {24, 24, 24};
  head.source = SourceType::F32;
  Volume v(head);
  float* p = reinterpret_cast<float*>(v.data());
  for (int64_t k = 0; k < 24; ++k)
    for (int64_t j = 0; j < 24; ++j)
      for (int64_t i = 0; i < 24; ++i)
        p[i + 24 * (j + 24 * k)] =
            float(std::sqrt(double((i - 11.5) * (i - 11.5) + (j - 11.5) * (j - 11.5) + (k - 11.5) * (k - 11.5))) - 6.0);
  v.finalize_statistics();
  ASSERT_EQ(v.border_histogram.size(), v.histogram.size());
  uint64_t faces = 0;
  for (uint64_t c : v.border_histogram) faces += c;
  EXPECT_EQ(faces, uint64_t(24 * 24 * 24 - 22 * 22 * 22));
  const ResolvedScene r = resolve_scene(parse_scene_text(R"({"volume": "sdf"})"), v);
  const double t = otsu_threshold(v.histogram, v.min_value, v.max_value), bin = (v.max_value - v.min_value) / 1024;
  EXPECT_EQ(r.tf.eval(v.max_value).a, 0.0);   // the corners
  EXPECT_EQ(r.tf.eval(t + 10 * bin).a, 0.0);  // the outside, from the split on (the mirror's ties: a few bins)
  EXPECT_GT(r.tf.eval(-3.0).a, 0.0);          // inside
  EXPECT_GT(r.tf.eval(-3.0).a, r.tf.eval(0.0).a);
}

TEST(FirstView, ThreeQuarterViewAtResetCameraDistance) {
  const glm::dvec3 lo(0, 0, 0), hi(10, 20, 30);
  const Camera c = default_camera(lo, hi);
  const glm::dvec3 d = c.eye - c.center;
  const double radius = glm::length(hi - lo) / 2;
  EXPECT_NEAR(glm::length(d), radius / std::sin(15.0 * M_PI / 180.0), 1e-9);  // VTK's ResetCamera
  const double az = 30 * M_PI / 180, el = 20 * M_PI / 180;
  const glm::dvec3 want(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  EXPECT_NEAR(glm::length(glm::normalize(d) - want), 0.0, 1e-12);
  EXPECT_EQ(c.up, glm::dvec3(0, 1, 0));
  const Camera straight = default_camera(lo, hi, 30.0, 0.0, 0.0);  // VTK's ResetCamera alone: from +z
  EXPECT_NEAR(glm::length(glm::normalize(straight.eye - straight.center) - glm::dvec3(0, 0, 1)), 0.0, 1e-12);
}

TEST(FirstView, ResolvedSceneSaysWhereItsTfCameFrom) {
  GeneratorSpec g;
  g.kind = GeneratorKind::Blobs;
  g.dims = {24, 24, 24};
  const Volume v = generate_volume(g);
  const ResolvedScene derived = resolve_scene(parse_scene_text(R"({"volume": "v"})"), v);
  EXPECT_TRUE(derived.tf_derived);
  EXPECT_TRUE(derived.warnings.empty());
  const ResolvedScene given =
      resolve_scene(parse_scene_text(R"({"volume": "v", "tf": {"points": [[0,0,0,0,0],[1,1,1,1,1]]}})"), v);
  EXPECT_FALSE(given.tf_derived);
  // Peaks without a TF: the derived TF has a peak, so there is nothing to warn about.
  const ResolvedScene peaks =
      resolve_scene(parse_scene_text(R"({"volume": "v", "render": {"classification": "peaks"}})"), v);
  EXPECT_EQ(find_peaks(peaks.tf).size(), 1u);
  EXPECT_TRUE(peaks.warnings.empty());
}

TEST(FirstView, PeaksWithATfWithoutAPeakWarn) {
  GeneratorSpec g;
  g.kind = GeneratorKind::Blobs;
  g.dims = {24, 24, 24};
  const Volume v = generate_volume(g);
  const std::string ramp = R"("tf": {"points": [[0,0,0,0,0],[1,1,1,1,1]]})";
  const ResolvedScene r =
      resolve_scene(parse_scene_text(R"({"volume": "v", )" + ramp + R"(, "render": {"classification": "peaks"}})"), v);
  EXPECT_TRUE(has_warning(r, "no opacity peak")) << (r.warnings.empty() ? "" : r.warnings[0]);
  // Not for DVR classifications, nor for peaks switched off by the mode.
  EXPECT_TRUE(resolve_scene(parse_scene_text(R"({"volume": "v", )" + ramp + "}"), v).warnings.empty());
  EXPECT_TRUE(resolve_scene(parse_scene_text(R"({"volume": "v", )" + ramp +
                                             R"(, "render": {"classification": "peaks", "peak_mode": "dvr_only"}})"),
                            v)
                  .warnings.empty());
  // A peak the data never reaches (8-bit blobs: values 0..255).
  const std::string far = R"("tf": {"points": [[0,0,0,0,0],[500,1,1,1,1],[600,0,0,0,0]]})";
  const ResolvedScene out =
      resolve_scene(parse_scene_text(R"({"volume": "v", )" + far + R"(, "render": {"classification": "peaks"}})"), v);
  EXPECT_TRUE(has_warning(out, "outside the data's range")) << (out.warnings.empty() ? "" : out.warnings[0]);
  // A peak inside the range: no warning.
  const std::string inside = R"("tf": {"points": [[0,0,0,0,0],[100,1,1,1,1],[120,0,0,0,0]]})";
  EXPECT_TRUE(
      resolve_scene(parse_scene_text(R"({"volume": "v", )" + inside + R"(, "render": {"classification": "peaks"}})"), v)
          .warnings.empty());
}
