// Ray textures on the GL ray caster (Raspe & Müller 2008): per-ray step, termination and
// blend, view- and volume-aligned, against no texture, the CPU twin and the converged image.
#include <cmath>

#include "gpu/ray_texture_scenes.h"
#include "reference/reference_renderer.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

std::shared_ptr<Volume> ml() { return test::ray_texture_volume(); }

const json& kTf = test::kRayTextureTf;

json camera(double azimuth_deg) {
  const double a = azimuth_deg * 3.14159265358979 / 180.0;
  return {{"eye", {20 + 90 * std::sin(a), 50, 20 + 90 * std::cos(a)}},
          {"center", {20, 20, 20}},
          {"up", {0, 1, 0}},
          {"fov_y", 30}};
}

json scene(json ray_texture, double azimuth = 20.0, json render = json::object()) {
  render["step"] = 2.0;
  if (!ray_texture.is_null()) render["ray_texture"] = ray_texture;
  return {{"image", {{"width", 96}, {"height", 96}}}, {"camera", camera(azimuth)}, {"tf", kTf}, {"render", render}};
}

json stroke(const char* channel, double u, double v, double radius, double value) {
  return {{"channel", channel}, {"center", {u, v}}, {"radius", radius}, {"value", value}};
}

json texture(const char* mapping, json strokes) {
  return {{"mapping", mapping}, {"size", {64, 64}}, {"strokes", strokes}};
}

// Largest channel difference at pixel i of two images.
float diff_at(const Image& a, const Image& b, size_t i) {
  float d = 0;
  for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(a.rgba[i * 4 + c] - b.rgba[i * 4 + c]));
  return d;
}

// Is pixel (x, y) of a 96^2 view-aligned image inside a stroke's disk (centre u, v; radius r)?
double disk_distance(int x, int y, double u, double v) { return std::hypot((x + 0.5) / 96 - u, (y + 0.5) / 96 - v); }

TEST(ray_texture, WithoutStrokesRendersAsNoTexturePixelForPixel) {
  auto v = ml();
  test::TestVolume gv(v);
  const Image none = test::render_gpu(gv, test::make_scene(*v, scene(nullptr)), render::RenderPath::Fragment);
  for (const char* mapping : {"view", "volume"}) {
    render::RenderStats st;
    const Image with = test::render_gpu(gv, test::make_scene(*v, scene(texture(mapping, json::array()))),
                                        render::RenderPath::Fragment, &st);
    EXPECT_NE(st.variant.find("+raytex"), std::string::npos) << st.variant;  // the code runs
    size_t differing = 0;
    for (size_t i = 0; i < none.rgba.size(); ++i) differing += none.rgba[i] != with.rgba[i];
    EXPECT_EQ(differing, 0u) << mapping;
  }
}

TEST(ray_texture, GpuMatchesTheCpuTwin) {
  auto v = ml();
  test::TestVolume gv(v);
  const json strokes = {stroke("step", 0.4, 0.5, 0.2, 0.25), stroke("termination", 0.7, 0.3, 0.15, 0.3),
                        stroke("blend", 0.3, 0.8, 0.2, 0.8)};
  for (const char* mapping : {"view", "volume"}) {
    const ResolvedScene s = test::make_scene(*v, scene(texture(mapping, strokes)));
    const Image g = test::render_gpu(gv, s, render::RenderPath::Fragment);
    const Image c = reference::render_reference(*v, s);
    const double psnr = reference::compare(g, c).psnr;
    std::printf("%s: GPU against CPU twin %.1f dB\n", mapping, psnr);
    EXPECT_GE(psnr, 50.0) << mapping;
  }
}

// A step stroke x1/4 lowers the error against the converged image inside its disk, x8 raises
// it, and no pixel outside the disk changes by more than 1/255.
TEST(ray_texture, StepStrokeChangesTheErrorInsideItsDiskOnly) {
  auto v = ml();
  test::TestVolume gv(v);
  const ResolvedScene plain = test::make_scene(*v, scene(nullptr));
  const auto conv = reference::render_converged(*v, plain, reference::OpticalModel::Dvr, 1e-4);
  ASSERT_TRUE(conv.converged);
  const Image base = test::render_gpu(gv, plain, render::RenderPath::Fragment);
  const double u = 0.5, vv = 0.45, radius = 0.2;
  for (double value : {0.25, 8.0}) {
    const Image img =
        test::render_gpu(gv, test::make_scene(*v, scene(texture("view", {stroke("step", u, vv, radius, value)}))),
                         render::RenderPath::Fragment);
    double err_in = 0, err_base_in = 0;
    int in = 0, outside_changed = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) {
        const size_t i = size_t(y) * 96 + size_t(x);
        const double d = disk_distance(x, y, u, vv);
        if (d < radius - 0.02) {
          err_in += std::pow(diff_at(img, conv.image, i), 2);
          err_base_in += std::pow(diff_at(base, conv.image, i), 2);
          ++in;
        } else if (d > radius + 0.02) {
          outside_changed += diff_at(img, base, i) > 1.0f / 255.0f;
        }
      }
    std::printf("step x%g: RMSE inside %.3e (no texture %.3e), %d pixels outside changed\n", value,
                std::sqrt(err_in / in), std::sqrt(err_base_in / in), outside_changed);
    EXPECT_GT(in, 500);
    EXPECT_EQ(outside_changed, 0);
    // Measured: x1/4 0.04x the squared error of no texture, x8 94x.
    if (value < 1) {
      EXPECT_LT(err_in, 0.25 * err_base_in);
    } else {
      EXPECT_GT(err_in, 4.0 * err_base_in);
    }
  }
}

// View-aligned edits stay on the screen when the camera turns; volume-aligned ones stay on
// the volume: the changed pixels move with it.
TEST(ray_texture, VolumeAlignedEditsFollowTheCameraViewAlignedOnesDoNot) {
  auto v = ml();
  test::TestVolume gv(v);
  auto changed = [&](const char* mapping, double azimuth) {
    const Image a = test::render_gpu(gv, test::make_scene(*v, scene(nullptr, azimuth)), render::RenderPath::Fragment);
    const json t = texture(mapping, {stroke("termination", 0.55, 0.5, 0.12, 0.05)});
    const Image b = test::render_gpu(gv, test::make_scene(*v, scene(t, azimuth)), render::RenderPath::Fragment);
    double sx = 0;
    int n = 0;
    for (size_t i = 0; i < a.rgba.size() / 4; ++i)
      if (diff_at(a, b, i) > 2.0f / 255.0f) sx += double(i % 96), ++n;
    return std::pair{n, n ? sx / n : -1.0};
  };
  const auto [nv0, xv0] = changed("view", 20.0);
  const auto [nv1, xv1] = changed("view", 35.0);
  const auto [no0, xo0] = changed("volume", 20.0);
  const auto [no1, xo1] = changed("volume", 35.0);
  std::printf("view: %d pixels at x %.1f, then %d at x %.1f; volume: %d at x %.1f, then %d at x %.1f\n", nv0, xv0, nv1,
              xv1, no0, xo0, no1, xo1);
  ASSERT_GT(nv0, 50);
  ASSERT_GT(no0, 20);
  ASSERT_GT(no1, 20);
  EXPECT_NEAR(xv1, xv0, 3.0);           // the view-aligned region stays put
  EXPECT_GT(std::abs(xo1 - xo0), 6.0);  // the volume-aligned one moves with the volume
}

// The termination and blend channels change only their region too.
TEST(ray_texture, TerminationAndBlendChangeOnlyTheirDisk) {
  auto v = ml();
  test::TestVolume gv(v);
  const Image base = test::render_gpu(gv, test::make_scene(*v, scene(nullptr)), render::RenderPath::Fragment);
  const double u = 0.45, vv = 0.55, radius = 0.18;
  for (const auto& [channel, value] : {std::pair{"termination", 0.05}, std::pair{"blend", 1.0}}) {
    const Image img =
        test::render_gpu(gv, test::make_scene(*v, scene(texture("view", {stroke(channel, u, vv, radius, value)}))),
                         render::RenderPath::Fragment);
    int inside_changed = 0, outside_changed = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) {
        const size_t i = size_t(y) * 96 + size_t(x);
        const double d = disk_distance(x, y, u, vv);
        const bool changed = diff_at(img, base, i) > 1.0f / 255.0f;
        if (d < radius - 0.02) inside_changed += changed;
        if (d > radius + 0.02) outside_changed += changed;
      }
    std::printf("%s: %d pixels changed inside, %d outside\n", channel, inside_changed, outside_changed);
    EXPECT_GT(inside_changed, 300) << channel;
    EXPECT_EQ(outside_changed, 0) << channel;
  }
}

}  // namespace
}  // namespace peakcast
