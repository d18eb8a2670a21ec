// `bench scene SCENE.json`: frame time of any user scene over an orbit, after warm-up, as a
// viewer pays it (8-bit frame read back, what the stream encodes, without sample counts), with
// samples per ray (one more frame at the start pose) and the variant. --json prints one object for
// scripts (scripts/bench_peers.py reads it).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "app/scene_file.h"
#include "render/backend.h"

namespace peakcast::bench {
namespace {

using app::load_scene_file;
using app::LoadedScene;

struct SceneBenchArgs {
  std::string scene, path = "fragment";
  int frames = 12, warmup = 2;
  double orbit = 30.0;
  bool json = false, bare = false;
};

// What the timed orbit measured: each frame's time, render ms and GPU ms, and the first warm-up frame's time.
struct OrbitTimes {
  std::vector<double> frame_ms, render_ms, gpu_ms;
  double first_frame_ms = 0;
};

// The warm-up frames and the n timed frames over the orbit, submitted and collected as a stream does.
OrbitTimes time_orbit(const SceneBenchArgs& a, render::Renderer& caster, const render::ResidentVolume& gv,
                      const ResolvedScene& scene, const render::RenderRequest& req, int n, render::RenderStats& st) {
  OrbitTimes t;
  // Frames go through submit and collect as the server's stream sends them: where the renderer
  // overlaps work (a GPU), frame f + 1 is drawn before frame f is collected. A frame's time is
  // from its submit, or the previous frame's collect if later, to its own collect.
  using Clock = std::chrono::steady_clock;
  std::vector<Clock::time_point> submitted;
  Clock::time_point last_done{};
  const bool overlap = caster.asynchronous();
  auto collect = [&](int f) {
    caster.collect(&st);
    const Clock::time_point done = Clock::now();
    const double ms = ms_between(std::max(submitted[size_t(f + a.warmup)], last_done), done);
    last_done = done;
    if (f == -a.warmup) t.first_frame_ms = ms;
    if (f < 0) return;
    t.frame_ms.push_back(ms);
    t.render_ms.push_back(st.render_ms);
    if (st.gpu_ms >= 0) t.gpu_ms.push_back(st.gpu_ms);
  };
  int next_collect = -a.warmup;
  for (int f = -a.warmup; f < n; ++f) {
    ResolvedScene s = scene;
    // Frames spread evenly over the orbit; warm-up frames at the start pose.
    s.camera = orbit_camera(scene.camera, f < 0 || n == 1 ? 0.0 : a.orbit * f / (n - 1));
    submitted.push_back(Clock::now());
    caster.submit(gv, s, req);
    if (!overlap || caster.in_flight() >= render::Renderer::kFramesInFlight) collect(next_collect++);
  }
  while (next_collect < n) collect(next_collect++);
  return t;
}

// What run_scene_bench measured, for the report.
struct SceneBenchResult {
  int n = 0;
  double load_ms = 0, upload_total_ms = 0;
  OrbitTimes orbit;
  double samples_per_ray = 0, gsamples_per_s = 0;
  std::string variant;
  std::vector<double> bare_ms, full_ms;
};

// The report as one JSON object (--json).
nlohmann::json scene_bench_json(const SceneBenchArgs& a, const BenchRenderer& b, const render::ResidentVolume& gv,
                                const ResolvedScene& scene, const SceneBenchResult& r) {
  const OrbitTimes& o = r.orbit;
  const auto [mn, mx] = std::minmax_element(o.frame_ms.begin(), o.frame_ms.end());
  nlohmann::json j = {{"scene", a.scene},
                      {"width", scene.scene.width},
                      {"height", scene.scene.height},
                      {"step", scene.step},
                      {"frames", r.n},
                      {"orbit_deg", a.orbit},
                      {"frame_ms_median", median(o.frame_ms)},
                      {"frame_ms_min", *mn},
                      {"frame_ms_max", *mx},
                      {"render_ms_median", median(o.render_ms)},
                      {"gsamples_per_s", r.gsamples_per_s},
                      {"samples_per_ray", r.samples_per_ray},
                      {"variant", r.variant},
                      {"load_ms", r.load_ms},
                      {"upload_ms", gv.upload_ms()},
                      {"macrocells_ms", gv.macrocell_ms()},
                      {"gpu_volume_ms", r.upload_total_ms},
                      {"first_frame_ms", o.first_frame_ms},
                      {"load_to_first_frame_ms", r.load_ms + r.upload_total_ms + o.first_frame_ms},
                      {"renderer", b.description()},
                      {"backend", render::to_string(b.backend)}};
  if (!o.gpu_ms.empty()) j["gpu_ms_median"] = median(o.gpu_ms);
  if (a.bare) {
    j["bare_ms"] = median(r.bare_ms);
    j["full_render_ms_float"] = median(r.full_ms);
  }
  return j;
}

// The report as text.
void print_scene_bench(const SceneBenchArgs& a, const BenchRenderer& b, const render::ResidentVolume& gv,
                       const ResolvedScene& scene, const SceneBenchResult& r) {
  const OrbitTimes& o = r.orbit;
  const auto [mn, mx] = std::minmax_element(o.frame_ms.begin(), o.frame_ms.end());
  std::printf("renderer: %s\nscene: %s (%dx%d, step %.4g, variant %s)\n", b.description().c_str(), a.scene.c_str(),
              scene.scene.width, scene.scene.height, scene.step, r.variant.c_str());
  std::printf(
      "load %.0f ms (file, range, histogram), upload %.0f ms, macrocells %.0f ms, first frame %.0f ms "
      "(shader compile included): load to first frame %.0f ms\n",
      r.load_ms, gv.upload_ms(), gv.macrocell_ms(), o.first_frame_ms, r.load_ms + r.upload_total_ms + o.first_frame_ms);
  std::printf(
      "%d frames over a %.0f-degree orbit after %d warm-up: frame ms median %.1f min %.1f max %.1f; "
      "render ms median %.1f%s; samples per ray %.1f, %.2f G samples/s\n",
      r.n, a.orbit, a.warmup, median(o.frame_ms), *mn, *mx, median(o.render_ms),
      o.gpu_ms.empty() ? "" : (", GPU ms median " + std::to_string(median(o.gpu_ms))).c_str(), r.samples_per_ray,
      r.gsamples_per_s);
  if (a.bare)
    std::printf(
        "bare sampling loop (same rays and samples, no TF, no compositing, no traversal): %.1f ms against "
        "%.1f ms for the full ray caster (float output): ratio %.2f\n",
        median(r.bare_ms), median(r.full_ms), median(r.full_ms) / median(r.bare_ms));
}

int run_scene_bench(const SceneBenchArgs& a) {
  SceneBenchResult r;
  const auto t_load = std::chrono::steady_clock::now();
  LoadedScene ls = load_scene_file(a.scene);
  r.load_ms = ms_between(t_load, std::chrono::steady_clock::now());
  BenchRenderer b = make_bench_renderer();
  render::Renderer& caster = *b.renderer;
  const auto t_upload = std::chrono::steady_clock::now();
  auto resident = caster.make_resident(ls.volume);  // upload (GL) + the trilinear macrocell grid
  const render::ResidentVolume& gv = *resident;
  r.upload_total_ms = ms_between(t_upload, std::chrono::steady_clock::now());
  render::RenderRequest req;
  req.path = a.path == "compute" ? render::RenderPath::Compute : render::RenderPath::Fragment;
  req.output = render::RenderOutput::Rgb8;  // what a viewer's stream renders: no sample counts
  render::RenderStats st;
  r.n = std::max(1, a.frames);
  r.orbit = time_orbit(a, caster, gv, ls.scene, req, r.n, st);
  // Samples per ray: one more frame at the start pose that reads the counts back.
  render::RenderRequest counted = req;
  counted.sample_stats = true;
  caster.render(gv, ls.scene, counted, &st);
  r.samples_per_ray = st.samples_mean;
  r.variant = st.variant;
  // Samples per second over the frame's own render time (the GPU's, where measured).
  const double work_ms = r.orbit.gpu_ms.empty() ? median(r.orbit.render_ms) : median(r.orbit.gpu_ms);
  r.gsamples_per_s = st.samples_total / std::max(work_ms, 1e-6) * 1e-6;
  // The ceiling: the bare sampling loop (same rays, same per-ray sample counts, reconstruction
  // only) at the start pose, against the full ray caster's render_ms there.
  if (a.bare) {
    ResolvedScene s = ls.scene;
    render::RenderStats fs, bs;
    for (int k = 0; k < 3; ++k) {
      const Image full = caster.render(gv, s, req.path, &fs);
      b.bench->render_bare(gv, s, req.path, full, &bs);
      r.full_ms.push_back(fs.render_ms);
      r.bare_ms.push_back(bs.render_ms);
    }
  }
  if (a.json) {
    std::printf("%s\n", scene_bench_json(a, b, gv, ls.scene, r).dump().c_str());
    return 0;
  }
  print_scene_bench(a, b, gv, ls.scene, r);
  return 0;
}

}  // namespace

void add_scene_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<SceneBenchArgs>();
  auto* c = bench.add_subcommand("scene", "Frame ms (median/min/max) of a scene file over an orbit");
  c->add_option("scene", a->scene, "scene JSON")->required()->check(CLI::ExistingFile);
  c->add_option("--frames", a->frames, "timed frames")->check(CLI::Range(1, 100000));
  c->add_option("--warmup", a->warmup, "untimed frames first (shader compile, uploads)")->check(CLI::Range(0, 1000));
  c->add_option("--orbit", a->orbit, "degrees turned about the camera's up axis over the timed frames")
      ->check(CLI::Range(-3600.0, 3600.0));
  c->add_option("--path", a->path, "fragment | compute")->check(CLI::IsMember({"fragment", "compute"}));
  c->add_flag("--json", a->json, "print one JSON object");
  c->add_flag("--bare", a->bare, "also time the bare sampling loop on the same rays (the ceiling)");
  c->callback([a, &run] { run = [a] { return run_scene_bench(*a); }; });
}

}  // namespace peakcast::bench
