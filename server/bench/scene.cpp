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

int run_scene_bench(const SceneBenchArgs& a) {
  const auto t_load = std::chrono::steady_clock::now();
  LoadedScene ls = load_scene_file(a.scene);
  const double load_ms = ms_between(t_load, std::chrono::steady_clock::now());
  BenchRenderer b = make_bench_renderer();
  render::Renderer& caster = *b.renderer;
  const auto t_upload = std::chrono::steady_clock::now();
  auto resident = caster.make_resident(ls.volume);  // upload (GL) + the trilinear macrocell grid
  const render::ResidentVolume& gv = *resident;
  const double upload_total_ms = ms_between(t_upload, std::chrono::steady_clock::now());
  double first_frame_ms = 0;
  render::RenderRequest req;
  req.path = a.path == "compute" ? render::RenderPath::Compute : render::RenderPath::Fragment;
  req.output = render::RenderOutput::Rgb8;  // what a viewer's stream renders: no sample counts
  std::vector<double> frame_ms, render_ms, gpu_ms;
  render::RenderStats st;
  const int n = std::max(1, a.frames);
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
    if (f == -a.warmup) first_frame_ms = ms;
    if (f < 0) return;
    frame_ms.push_back(ms);
    render_ms.push_back(st.render_ms);
    if (st.gpu_ms >= 0) gpu_ms.push_back(st.gpu_ms);
  };
  int next_collect = -a.warmup;
  for (int f = -a.warmup; f < n; ++f) {
    ResolvedScene s = ls.scene;
    // Frames spread evenly over the orbit; warm-up frames at the start pose.
    s.camera = orbit_camera(ls.scene.camera, f < 0 || n == 1 ? 0.0 : a.orbit * f / (n - 1));
    submitted.push_back(Clock::now());
    caster.submit(gv, s, req);
    if (!overlap || caster.in_flight() >= render::Renderer::kFramesInFlight) collect(next_collect++);
  }
  while (next_collect < n) collect(next_collect++);
  // Samples per ray: one more frame at the start pose that reads the counts back.
  render::RenderRequest counted = req;
  counted.sample_stats = true;
  caster.render(gv, ls.scene, counted, &st);
  const double samples_per_ray = st.samples_mean;
  // Samples per second over the frame's own render time (the GPU's, where measured).
  const double work_ms = gpu_ms.empty() ? median(render_ms) : median(gpu_ms);
  const double gsamples_per_s = st.samples_total / std::max(work_ms, 1e-6) * 1e-6;
  // The ceiling: the bare sampling loop (same rays, same per-ray sample counts, reconstruction
  // only) at the start pose, against the full ray caster's render_ms there.
  std::vector<double> bare_ms, full_ms;
  if (a.bare) {
    ResolvedScene s = ls.scene;
    render::RenderStats fs, bs;
    for (int k = 0; k < 3; ++k) {
      const Image full = caster.render(gv, s, req.path, &fs);
      b.bench->render_bare(gv, s, req.path, full, &bs);
      full_ms.push_back(fs.render_ms);
      bare_ms.push_back(bs.render_ms);
    }
  }
  const auto [mn, mx] = std::minmax_element(frame_ms.begin(), frame_ms.end());
  nlohmann::json j = {{"scene", a.scene},
                      {"width", ls.scene.scene.width},
                      {"height", ls.scene.scene.height},
                      {"step", ls.scene.step},
                      {"frames", n},
                      {"orbit_deg", a.orbit},
                      {"frame_ms_median", median(frame_ms)},
                      {"frame_ms_min", *mn},
                      {"frame_ms_max", *mx},
                      {"render_ms_median", median(render_ms)},
                      {"gsamples_per_s", gsamples_per_s},
                      {"samples_per_ray", samples_per_ray},
                      {"variant", st.variant},
                      {"load_ms", load_ms},
                      {"upload_ms", gv.upload_ms()},
                      {"macrocells_ms", gv.macrocell_ms()},
                      {"gpu_volume_ms", upload_total_ms},
                      {"first_frame_ms", first_frame_ms},
                      {"load_to_first_frame_ms", load_ms + upload_total_ms + first_frame_ms},
                      {"renderer", b.description()},
                      {"backend", render::to_string(b.backend)}};
  if (!gpu_ms.empty()) j["gpu_ms_median"] = median(gpu_ms);
  if (a.bare) {
    j["bare_ms"] = median(bare_ms);
    j["full_render_ms_float"] = median(full_ms);
  }
  if (a.json) {
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("renderer: %s\nscene: %s (%dx%d, step %.4g, variant %s)\n", b.description().c_str(), a.scene.c_str(),
              ls.scene.scene.width, ls.scene.scene.height, ls.scene.step, st.variant.c_str());
  std::printf(
      "load %.0f ms (file, range, histogram), upload %.0f ms, macrocells %.0f ms, first frame %.0f ms "
      "(shader compile included): load to first frame %.0f ms\n",
      load_ms, gv.upload_ms(), gv.macrocell_ms(), first_frame_ms, load_ms + upload_total_ms + first_frame_ms);
  std::printf(
      "%d frames over a %.0f-degree orbit after %d warm-up: frame ms median %.1f min %.1f max %.1f; "
      "render ms median %.1f%s; samples per ray %.1f, %.2f G samples/s\n",
      n, a.orbit, a.warmup, median(frame_ms), *mn, *mx, median(render_ms),
      gpu_ms.empty() ? "" : (", GPU ms median " + std::to_string(median(gpu_ms))).c_str(), samples_per_ray,
      gsamples_per_s);
  if (a.bare)
    std::printf(
        "bare sampling loop (same rays and samples, no TF, no compositing, no traversal): %.1f ms against "
        "%.1f ms for the full ray caster (float output): ratio %.2f\n",
        median(bare_ms), median(full_ms), median(full_ms) / median(bare_ms));
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
