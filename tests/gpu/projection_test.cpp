// Intensity projections (classifications mip, minip, average; shaders/ray/projection.glsl) on
// the backend under test (GL, or the CPU backend as cpu.Projections.*): each against the CPU
// reference over scenes x sampling methods, the three ordered as they must be, one never
// mistaken for another, early termination exact and taken, and clipping.
#include <cmath>

#include <glm/geometric.hpp>

#include "core/volume_io.h"
#include "gpu/gpu_fixture.h"
#include "reference/metrics.h"
#include "reference/reference_renderer.h"
#include "unit/test_util.h"

using namespace peakcast;
using nlohmann::json;

namespace {

// A grey ramp over the volume's range from `from` (transparent) to the top (opaque white): the
// TF of a classic MIP, and monotone, so a larger projected value is a brighter pixel.
json grey_ramp(const Volume& v, double from) {
  auto at = [&](double f) { return v.min_value + f * (v.max_value - v.min_value); };
  return {{"points", {{at(0.0), 0, 0, 0, 0}, {at(from), 0, 0, 0, 0}, {at(1.0), 1, 1, 1, 1}}}};
}
// A coloured TF with a band and a dip: the projected value's colour matters, not only its size.
json coloured(const Volume& v) {
  auto at = [&](double f) { return v.min_value + f * (v.max_value - v.min_value); };
  return {{"points",
           {{at(0.0), 0.1, 0.1, 0.4, 0.0},
            {at(0.25), 0.2, 0.4, 1.0, 0.3},
            {at(0.5), 1.0, 0.6, 0.1, 0.8},
            {at(0.6), 0.9, 0.2, 0.2, 0.4},
            {at(1.0), 1.0, 1.0, 0.9, 1.0}}}};
}

json camera_for(const Volume& v, glm::dvec3 dir) {
  const glm::dvec3 c = v.origin + v.extent() * 0.5;
  const double r = glm::length(v.extent()) * 0.5;
  const glm::dvec3 eye = c + glm::normalize(dir) * (r / std::sin(15.0 * M_PI / 180.0));
  return {{"eye", {eye.x, eye.y, eye.z}}, {"center", {c.x, c.y, c.z}}, {"up", {0, 1, 0}}, {"fov_y", 30}};
}

struct Scene {
  const char* name;
  std::function<std::shared_ptr<Volume>()> volume;
};
std::vector<Scene> scenes() {
  return {
      {"blobs_u8_aniso",
       [] {
         return test::make_volume(GeneratorKind::Blobs, {48, 40, 44}, SourceType::U8, {1, 1.25, 1});
       }},
      {"nucleon_real", [] { return std::make_shared<Volume>(load_volume(test::data_dir() / "nucleon.nhdr")); }},
      {"headsq_int16_aniso",
       [] { return std::make_shared<Volume>(load_volume(test::data_dir() / "headsq/quarter.nhdr")); }},
  };
}

struct Method {
  const char* name;
  json render;  // merged into the scene's render (the classification is added)
};
std::vector<Method> methods() {
  return {
      {"uniform", json::object()},
      {"tricubic", {{"filter", "tricubic"}}},
      {"differential", {{"sampling", "differential"}, {"s_k", 2}}},
      {"adaptive", {{"adaptive", true}}},
      {"virtual_samples", {{"virtual_samples", 3}, {"step", 2.0}}},
      {"ortho", json::object()},  // (the camera is made orthographic below)
  };
}

ResolvedScene scene_for(const Volume& v, const char* classification, const Method& m, const json& tf) {
  json render = m.render;
  render["classification"] = classification;
  json camera = camera_for(v, {1.0, 0.7, 1.6});
  if (std::string(m.name) == "ortho") {
    camera.erase("fov_y");
    camera["projection"] = "orthographic";
    camera["height"] = 1.2 * glm::length(v.extent());
  }
  return test::make_scene(
      v, {{"image", {{"width", 96}, {"height", 80}}}, {"tf", tf}, {"camera", camera}, {"render", render}});
}

const char* const kProjections[] = {"mip", "minip", "average"};

// Measured against the reference (96x80, the three scenes, six methods, coloured TF): GL on
// llvmpipe (Mesa 22.3.6) 55.0-138.4 dB, worst pixel 0.0227 (the 8-bit blobs: llvmpipe filters
// 8-bit textures with 8-bit weights); the CPU backend 120.4-180.4 dB, worst pixel 1e-4. A
// projection drawn as another one scores 12.2-19.1 dB (AProjectionIsNotAnother). GL is held to
// 45 dB and 0.05 per pixel (room for other GPUs' filter weights), the CPU backend, which filters
// in float as the reference does, to 110 dB. A maximum that skips cells it should not (cells
// within 0.05 of the running maximum) scores 46.0-53.1 dB with worst pixels of 0.08-0.15 on GL:
// caught by the per-pixel bound on GL and by the 110 dB on the CPU.
constexpr double kMinPsnrGl = 45.0, kMaxPixelGl = 0.05, kMinPsnrCpu = 110.0;

TEST(Projections, EveryMethodMatchesTheReference) {
  for (const Scene& sc : scenes()) {
    auto v = sc.volume();
    test::TestVolume gv(v);
    for (const char* p : kProjections)
      for (const Method& m : methods()) {
        const ResolvedScene s = scene_for(*v, p, m, coloured(*v));
        render::RenderStats st;
        const Image g = test::render_gpu(gv, s, render::RenderPath::Fragment, &st);
        const Image ref = reference::render_reference(*v, s);
        const auto e = reference::compare(g, ref);
        std::printf("%-20s %-8s %-16s PSNR %6.1f dB, max %.4f, samples/ray %.1f [%s]\n", sc.name, p, m.name, e.psnr,
                    e.max_abs, st.samples_mean, st.variant.c_str());
        const bool cpu = test::cpu_backend();
        const bool good = cpu ? e.psnr >= kMinPsnrCpu : e.psnr >= kMinPsnrGl && e.max_abs <= kMaxPixelGl;
        EXPECT_TRUE(good) << sc.name << " " << p << " " << m.name << ": " << e.psnr << " dB, worst pixel " << e.max_abs;
        EXPECT_NE(st.variant.find(std::string("+") + p), std::string::npos) << st.variant;
        EXPECT_TRUE(test::all_finite(g));
        if (!good) test::save_artifacts(g, ref, std::string("projection_") + sc.name + "_" + p + "_" + m.name);
      }
  }
}

// With a monotone TF a pixel's brightness orders as its value: MIP >= average >= MinIP on every
// pixel, and the three differ (the pictures are not one picture three times).
TEST(Projections, MaximumAverageAndMinimumAreOrdered) {
  auto v = scenes()[1].volume();
  test::TestVolume gv(v);
  const Method uniform = methods()[0];
  Image img[3];
  for (int k = 0; k < 3; ++k)
    img[k] =
        test::render_gpu(gv, scene_for(*v, kProjections[k], uniform, grey_ramp(*v, 0.0)), render::RenderPath::Fragment);
  size_t out_of_order = 0;
  double mip_sum = 0, avg_sum = 0, min_sum = 0;
  for (size_t i = 0; i < img[0].rgba.size(); i += 4) {
    const double mx = img[0].rgba[i], avg = img[2].rgba[i], mn = img[1].rgba[i];
    out_of_order += (mx + 1e-5 < avg || avg + 1e-5 < mn) ? 1 : 0;
    mip_sum += mx, avg_sum += avg, min_sum += mn;
  }
  std::printf("mean red: mip %.4f, average %.4f, minip %.4f\n", mip_sum, avg_sum, min_sum);
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_GT(mip_sum, 1.5 * avg_sum);
  EXPECT_GT(avg_sum, 1.5 * min_sum + 1e-9);
}

// What a wrong projection would score: each backend picture against the other projections'
// references stays far below the bounds above, so they tell them apart.
TEST(Projections, AProjectionIsNotAnother) {
  auto v = scenes()[0].volume();
  test::TestVolume gv(v);
  const Method uniform = methods()[0];
  for (const char* p : kProjections) {
    const Image g = test::render_gpu(gv, scene_for(*v, p, uniform, coloured(*v)), render::RenderPath::Fragment);
    for (const char* other : {"mip", "minip", "average", "post"}) {
      if (std::string(other) == p) continue;
      const auto e =
          reference::compare(g, reference::render_reference(*v, scene_for(*v, other, uniform, coloured(*v))));
      std::printf("%-8s against the %-8s reference: %.1f dB\n", p, other, e.psnr);
      EXPECT_LT(e.psnr, 30.0) << p << " vs " << other;
    }
  }
}

// A slab at the volume's maximum in front of dimmer data: MIP rays that cross it stop there (its
// value is the top of the range, which no later sample exceeds), so they take fewer samples than
// the average's rays, and the picture is still the reference's, which never stops early.
TEST(Projections, MipStopsWhereNoSampleCanExceedItAndStaysExact) {
  auto v = test::float_volume({40, 32, 36}, [](int64_t x, int64_t y, int64_t z) {
    if (x >= 30) return 1.0f;  // the slab, nearest the camera below
    return 0.2f + 0.3f * float((x * 7 + y * 13 + z * 5) % 17) / 17.0f;
  });
  test::TestVolume gv(v);
  const Method uniform = methods()[0];
  ResolvedScene s_mip = scene_for(*v, "mip", uniform, grey_ramp(*v, 0.1));
  ResolvedScene s_avg = scene_for(*v, "average", uniform, grey_ramp(*v, 0.1));
  // Look along -x, so the slab (x >= 30) is what the rays cross first.
  for (ResolvedScene* s : {&s_mip, &s_avg}) {
    const glm::dvec3 c = (s->box_min + s->box_max) * 0.5;
    s->camera.eye = c + glm::dvec3(160, 20, 30);
    s->camera.center = c;
  }
  render::RenderStats st_mip, st_avg;
  const Image a = test::render_gpu(gv, s_mip, render::RenderPath::Fragment, &st_mip);
  test::render_gpu(gv, s_avg, render::RenderPath::Fragment, &st_avg);
  const auto e = reference::compare(a, reference::render_reference(*v, s_mip));
  std::printf("samples/ray: mip %.1f, average %.1f; mip vs reference %.1f dB, max %.2e\n", st_mip.samples_mean,
              st_avg.samples_mean, e.psnr, e.max_abs);
  EXPECT_LT(st_mip.samples_mean, 0.5 * st_avg.samples_mean) << "MIP rays must stop at the slab";
  EXPECT_LE(e.max_abs, 1e-5);
}

// The CPU backend's fast path for projections (project_loop, over the rest of a ray or an occupied
// cell's points) against the shared walk without it: bit for bit, pixels and sample counts, with
// uniform and differential steps, tricubic, adaptive multipliers (the cell walk's cells of
// multiplier 1) and a ray texture's step multiplier.
TEST(Projections, CpuFastPathEqualsTheSharedWalk) {
  auto* cpu = test::gpu().cpu;
  if (!cpu) GTEST_SKIP() << "CPU backend only";
  const json texture = {{"mapping", "view"},
                        {"size", {32, 32}},
                        {"strokes", {{{"channel", "step"}, {"center", {0.5, 0.5}}, {"radius", 0.4}, {"value", 0.6}}}}};
  for (int scene : {0, 1}) {
    auto v = scenes()[size_t(scene)].volume();
    test::TestVolume gv(v);
    for (const char* p : kProjections)
      for (const Method& m : {methods()[0], methods()[1], methods()[2], methods()[3],
                              Method{"ray_texture", {{"ray_texture", texture}}}}) {
        const ResolvedScene s = scene_for(*v, p, m, coloured(*v));
        render::RenderStats st_fast, st_shared;
        const Image fast = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_fast);
        cpu->set_dense_runs(false);
        const Image shared = test::render_gpu(gv, s, render::RenderPath::Fragment, &st_shared);
        cpu->set_dense_runs(true);
        SCOPED_TRACE(std::string(p) + " " + m.name + " " + st_fast.variant);
        EXPECT_GT(st_shared.samples_mean, 3.0);
        EXPECT_EQ(fast.rgba, shared.rgba);
        EXPECT_EQ(fast.samples, shared.samples);
      }
  }
}

// A ray texture's termination does not stop a projection (its opacity does not accumulate): a
// termination of 0 everywhere, with virtual samples (whose window's end tests the stop), draws
// exactly what no ray texture draws; its blend still weighs the projected opacity.
TEST(Projections, ARayTexturesTerminationDoesNotStopThem) {
  auto v = scenes()[0].volume();
  test::TestVolume gv(v);
  const Method vs = methods()[4];
  for (const char* p : kProjections) {
    Method stop = vs;
    stop.render["ray_texture"] = {
        {"mapping", "view"},
        {"size", {16, 16}},
        {"strokes", {{{"channel", "termination"}, {"center", {0.5, 0.5}}, {"radius", 1.0}, {"value", 0.0}}}}};
    const Image plain = test::render_gpu(gv, scene_for(*v, p, vs, coloured(*v)), render::RenderPath::Fragment);
    const ResolvedScene stopped = scene_for(*v, p, stop, coloured(*v));
    const Image g = test::render_gpu(gv, stopped, render::RenderPath::Fragment);
    EXPECT_EQ(g.rgba, plain.rgba) << p;
    const auto e = reference::compare(g, reference::render_reference(*v, stopped));
    EXPECT_GE(e.psnr, test::cpu_backend() ? kMinPsnrCpu : kMinPsnrGl) << p;
  }
}

// render.clip cuts a projection's rays as it does DVR's: the clipped MIP matches the clipped
// reference, and differs from the unclipped picture.
TEST(Projections, ClippedLikeEveryMethod) {
  auto v = scenes()[0].volume();
  test::TestVolume gv(v);
  const glm::dvec3 lo = v->origin, hi = v->origin + v->extent(), c = (lo + hi) * 0.5;
  for (const char* p : kProjections) {
    Method m{"clipped",
             {{"clip",
               {{"box", {{lo.x - 1, lo.y + 0.3 * (hi.y - lo.y), lo.z - 1}, {hi.x + 1, hi.y + 1, hi.z}}},
                {"plane", {{"point", {c.x, c.y, c.z}}, {"normal", {-1.0, 0.3, 0.4}}}}}}}};
    const ResolvedScene clipped = scene_for(*v, p, m, coloured(*v));
    const ResolvedScene whole = scene_for(*v, p, methods()[0], coloured(*v));
    const Image g = test::render_gpu(gv, clipped, render::RenderPath::Compute);
    const auto e = reference::compare(g, reference::render_reference(*v, clipped));
    const auto cut = reference::compare(test::render_gpu(gv, whole, render::RenderPath::Compute), g);
    std::printf("%-8s clipped vs reference %.1f dB; vs unclipped %.1f dB\n", p, e.psnr, cut.psnr);
    EXPECT_GE(e.psnr, test::cpu_backend() ? kMinPsnrCpu : kMinPsnrGl) << p;
    EXPECT_LT(cut.psnr, 35.0) << p << ": the clip must change the picture";
  }
}

}  // namespace
