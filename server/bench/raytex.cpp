// `bench raytex`: Raspe & Müller 2008, Table 1 — frame time of plain ray casting, with a static
// ray texture, and while strokes are painted: one stroke per frame, direct (level 0) against
// hierarchical (level L), and direct with the whole texture uploaded again each frame (what a
// renderer without dirty regions pays). Cases take turns frame by frame over one orbit, so
// drift on the machine hits them alike.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "render/backend.h"

namespace peakcast::bench {
namespace {

using Clock = std::chrono::steady_clock;

struct RaytexArgs {
  std::string volume = "blobs";
  int size = 512;
  int frames = 24;
  double orbit = 15.0;  // degrees per frame
  double radius = 0.06;
  int level = 3;
};

enum class Kind { None, StaticDefaults, StaticPainted, Direct, Hierarchical, DirectFullUpload };

struct Case {
  const char* name;
  Kind kind;
  std::shared_ptr<const RayTextureSpec> spec;
  std::vector<double> frame_ms, update_ms, texels;
};

Stroke stroke_at(int i, double radius, int level) {
  // Strokes along a circle through the image, as a user's drag: step x1/2 inside the disk.
  const double a = 0.35 * i;
  Stroke s;
  s.channel = RayChannel::Step;
  s.u = 0.5 + 0.3 * std::cos(a);
  s.v = 0.5 + 0.3 * std::sin(a);
  s.radius = radius;
  s.falloff = 0.5;
  s.value = 0.5;
  s.level = level;
  return s;
}

std::shared_ptr<const RayTextureSpec> empty_texture(int size) {
  return std::make_shared<const RayTextureSpec>(
      parse_ray_texture({{"mapping", "view"}, {"size", {size, size}}}));  // the viewport's size, as in Raspe
}

void run_raytex(const RaytexArgs& a) {
  BenchRenderer gl = make_bench_renderer();
  render::Renderer& caster = *gl.renderer;
  auto vol = bench_volume(a.volume);
  auto resident = caster.make_resident(vol);
  const render::ResidentVolume& gv = *resident;
  std::printf("volume: %s, image %dx%d, ray texture %dx%d (view), stroke radius %.3f, %d frames over %.0f deg each\n",
              vol->to_string().c_str(), a.size, a.size, a.size, a.size, a.radius, a.frames, a.orbit);
  const ResolvedScene base = bench_scene(*vol, a.size, "trilinear");
  std::vector<Case> cases = {
      {"ray casting (RC)", Kind::None, nullptr, {}, {}, {}},
      {"RC + static ray texture (defaults)", Kind::StaticDefaults, empty_texture(a.size), {}, {}, {}},
      {"RC + static ray texture (40 strokes)", Kind::StaticPainted, empty_texture(a.size), {}, {}, {}},
      {"direct update (level 0)", Kind::Direct, empty_texture(a.size), {}, {}, {}},
      {"hierarchical update (level L)", Kind::Hierarchical, empty_texture(a.size), {}, {}, {}},
      {"direct, whole texture uploaded", Kind::DirectFullUpload, empty_texture(a.size), {}, {}, {}}};
  for (int i = 0; i < 40; ++i) cases[2].spec = with_stroke(*cases[2].spec, stroke_at(i, a.radius, 0));
  std::vector<Stroke> painted;           // the full-upload case's strokes so far
  for (int f = 0; f <= a.frames; ++f) {  // frame 0 warms up: shader compiles, first texture
    ResolvedScene s = base;
    const double ang = a.orbit * f * 3.14159265358979 / 180.0;
    const glm::dvec3 c = s.camera.center, e = s.camera.eye - c;
    s.camera.eye =
        c + glm::dvec3(e.x * std::cos(ang) - e.z * std::sin(ang), e.y, e.x * std::sin(ang) + e.z * std::cos(ang));
    painted.push_back(stroke_at(f, a.radius, 0));
    for (auto& k : cases) {
      if (k.kind == Kind::Direct) k.spec = with_stroke(*k.spec, stroke_at(f, a.radius, 0));
      if (k.kind == Kind::Hierarchical) k.spec = with_stroke(*k.spec, stroke_at(f, a.radius, a.level));
      if (k.kind == Kind::DirectFullUpload) {  // a new lineage each frame: built and uploaded whole
        auto fresh = std::make_shared<RayTextureSpec>(*empty_texture(a.size));
        fresh->strokes = painted;
        k.spec = fresh;
      }
      s.scene.render.ray_texture = k.spec;
      s.ray_texture = k.spec;
      render::RenderStats st;
      render::RenderRequest req;
      req.output = render::RenderOutput::Rgb8;  // what a streamed frame reads back
      const auto t0 = Clock::now();
      caster.render(gv, s, req, &st);
      const double ms = ms_between(t0, Clock::now());
      if (f == 0) continue;
      k.frame_ms.push_back(ms);
      k.update_ms.push_back(st.ray_texture_ms);
      k.texels.push_back(double(st.ray_texture_texels));
    }
  }
  const double rc = median(cases[0].frame_ms);
  std::printf("%-38s %9s %7s %10s %14s %8s\n", "case", "frame_ms", "fps", "update_ms", "texels/frame", "ratio");
  for (const auto& k : cases)
    std::printf("%-38s %9.2f %7.1f %10.3f %14.0f %8.3f\n", k.name, median(k.frame_ms), 1000.0 / median(k.frame_ms),
                median(k.update_ms), median(k.texels), median(k.frame_ms) / rc);
  std::printf(
      "medians of %d frames (Rgb8 read-back, the render thread's time per frame); update_ms: strokes applied "
      "on the host + upload, inside frame_ms; level L = %d; ratio: frame_ms / RC's\n",
      a.frames, a.level);
}

}  // namespace

void add_raytex_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<RaytexArgs>();
  auto* c = bench.add_subcommand("raytex",
                                 "Raspe Table 1: ray casting without, with a static, and with a painted "
                                 "ray texture (direct vs hierarchical updates)");
  c->add_option("--volume", a->volume, "volume file, or a generator kind made in memory (default blobs 256^3)");
  c->add_option("--size", a->size, "square image (and ray texture) size")->check(CLI::Range(16, 2048));
  c->add_option("--frames", a->frames, "timed frames per case (after one warm-up)")->check(CLI::Range(1, 1000));
  c->add_option("--orbit", a->orbit, "degrees the camera turns per frame")->check(CLI::Range(0.0, 360.0));
  c->add_option("--radius", a->radius, "stroke radius, texture units")->check(CLI::Range(0.001, 1.0));
  c->add_option("--level", a->level, "level of the hierarchical strokes")->check(CLI::Range(1, kMaxStrokeLevel));
  c->callback([a, &run] {
    run = [a] {
      run_raytex(*a);
      return 0;
    };
  });
}

}  // namespace peakcast::bench
