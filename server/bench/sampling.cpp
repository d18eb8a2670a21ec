// `bench sampling`: Knoll Table 2 style. Uniform against differential sampling (and each with
// adaptive sampling), and Lee Table 1 style virtual samples, on a close and a far camera: GPU frame time (median),
// samples per ray and PSNR against the converged image of the same scene, so equal-time and equal-error pairs can be
// read off. A benchmark command, not a test.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <tuple>

#include <glm/geometric.hpp>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "core/volume_io.h"
#include "reference/reference_renderer.h"
#include "reference/metrics.h"
#include "render/backend.h"

namespace fs = std::filesystem;

namespace peakcast::bench {
namespace {

struct SamplingBenchArgs {
  std::vector<std::string> volumes;
  int size = 128;
  int frames = 3;
};

// One case's median frame ms, samples per ray and last image.
struct Timed {
  double ms = 0, spr = 0;
  Image img;
};

// Renders a scene once to warm up and `frames` times timed.
Timed time_render(render::Renderer& caster, int frames, const render::ResidentVolume& gv, const ResolvedScene& s) {
  Timed t;
  std::vector<double> ms;
  render::RenderStats st;
  for (int f = 0; f <= frames; ++f) {
    t.img = caster.render(gv, s, render::RenderPath::Fragment, &st);
    if (f > 0) ms.push_back(st.render_ms);
  }
  t.ms = median(ms);
  t.spr = st.samples_mean;
  return t;
}

// The rows of one view: uniform and differential sweeps, each with adaptive sampling, and virtual samples.
std::vector<std::pair<std::string, nlohmann::json>> sampling_methods(const Volume& vol) {
  std::vector<std::pair<std::string, nlohmann::json>> methods;
  for (double step : {2.0, 1.0, 0.5, 0.25})
    methods.push_back({"uniform step " + std::to_string(step).substr(0, 4), {{"step", step * vol.spacing.x}}});
  for (double sk : {8.0, 4.0, 2.0, 1.0, 0.5, 0.25})
    methods.push_back(
        {"differential s_k " + std::to_string(sk).substr(0, 4), {{"sampling", "differential"}, {"s_k", sk}}});
  methods.push_back({"uniform 0.5 + adaptive", {{"step", 0.5 * vol.spacing.x}, {"adaptive", true}}});
  methods.push_back({"differential 2 + adaptive", {{"sampling", "differential"}, {"s_k", 2.0}, {"adaptive", true}}});
  // Lee Table 1 style: tricubic at step 1 with 0, 3 or 7 virtual samples against step 1/4.
  for (const auto& [name, step, vs] :
       {std::tuple{"tricubic x1", 1.0, 0}, std::tuple{"tricubic x4", 0.25, 0}, std::tuple{"tricubic x1 + vs3", 1.0, 3},
        std::tuple{"tricubic x1 + vs7", 1.0, 7}})
    methods.push_back({name, {{"filter", "tricubic"}, {"step", step * vol.spacing.x}, {"virtual_samples", vs}}});
  return methods;
}

// One volume seen from one view: what every row is measured on.
struct SamplingView {
  render::Renderer& caster;
  const SamplingBenchArgs& a;
  const Volume& vol;
  const render::ResidentVolume& gv;
  const char* view;
  const nlohmann::json& jv;  // the scene with the view's camera
};

// Every method of the view, its PSNR against the converged image of the same filter.
void time_sampling_methods(const SamplingView& v) {
  const ResolvedScene sv = resolve_scene(parse_scene(v.jv), v.vol);
  const auto conv = reference::render_converged(v.vol, sv, reference::OpticalModel::Dvr, 1e-4);
  nlohmann::json jc = v.jv;  // tricubic rows are judged against the tricubic field's own limit
  jc["render"]["filter"] = "tricubic";
  const auto conv_cubic =
      reference::render_converged(v.vol, resolve_scene(parse_scene(jc), v.vol), reference::OpticalModel::Dvr, 1e-4);
  for (const auto& [name, render] : sampling_methods(v.vol)) {
    nlohmann::json jm = v.jv;
    jm["render"].update(render);
    const ResolvedScene s = resolve_scene(parse_scene(jm), v.vol);
    const Timed t = time_render(v.caster, v.a.frames, v.gv, s);
    std::printf(
        "%-16s %-5s %-26s %9.2f %8.1f %9.2f\n", v.vol.name.c_str(), v.view, name.c_str(), t.ms, t.spr,
        reference::compare(t.img, s.scene.render.filter == Filter::Tricubic ? conv_cubic.image : conv.image).psnr);
    std::fflush(stdout);
  }
}

// Differential sampling at half size against uniform sampling at the step that visits as many samples.
void time_interactive(const SamplingView& v) {
  // Interactive frames are rendered at half size (quality.interactive_scale): a differential
  // scene keeps its s_k, so the larger footprint makes the steps twice as long. The
  // alternative: uniform sampling at the step that costs the same (visited samples matched).
  nlohmann::json jh = v.jv;
  jh["image"] = {{"width", v.a.size / 2}, {"height", v.a.size / 2}};
  const auto conv_half =
      reference::render_converged(v.vol, resolve_scene(parse_scene(jh), v.vol), reference::OpticalModel::Dvr, 1e-4);
  for (double sk : {4.0, 1.0, 0.25}) {
    nlohmann::json jd = jh;
    jd["render"].update({{"sampling", "differential"}, {"s_k", sk}});
    const Timed d = time_render(v.caster, v.a.frames, v.gv, resolve_scene(parse_scene(jd), v.vol));
    double step = v.vol.spacing.x;
    Timed u;
    for (int k = 0; k < 6; ++k) {
      nlohmann::json ju = jh;
      ju["render"]["step"] = step;
      u = time_render(v.caster, v.a.frames, v.gv, resolve_scene(parse_scene(ju), v.vol));
      if (std::abs(u.spr / d.spr - 1.0) < 0.02) break;
      step *= u.spr / d.spr;
    }
    std::printf(
        "%-16s %-5s interactive %3d^2: differential s_k %.2f %6.2f ms %6.1f spr %6.2f dB | uniform step "
        "%.3f %6.2f ms %6.1f spr %6.2f dB\n",
        v.vol.name.c_str(), v.view, v.a.size / 2, sk, d.ms, d.spr, reference::compare(d.img, conv_half.image).psnr,
        step, u.ms, u.spr, reference::compare(u.img, conv_half.image).psnr);
    std::fflush(stdout);
  }
}

int run_sampling_bench(const SamplingBenchArgs& a) {
  BenchRenderer b = make_bench_renderer();
  render::Renderer& caster = *b.renderer;
  std::printf("%-16s %-5s %-26s %9s %8s %9s\n", "volume", "view", "method", "median_ms", "spr", "PSNR_dB");
  for (const auto& path : a.volumes) {
    auto vol = std::make_shared<Volume>(load_volume(path));
    auto resident = caster.make_resident(vol);
    const render::ResidentVolume& gv = *resident;
    const double lo = vol->min_value, hi = vol->max_value;
    nlohmann::json j = {{"volume", vol->name}, {"image", {{"width", a.size}, {"height", a.size}}}};
    j["tf"] = {{"points",
                {{lo, 0, 0, 0, 0},
                 {lo + 0.3 * (hi - lo), 0.2, 0.4, 1.0, 0.0},
                 {lo + 0.6 * (hi - lo), 1.0, 0.8, 0.4, 0.3},
                 {hi, 1, 1, 1, 0.6}}}};
    j["render"] = {{"early_termination", 1.0}};
    const ResolvedScene base = resolve_scene(parse_scene(j), *vol);
    const glm::dvec3 c = base.camera.center;
    const glm::dvec3 dir = glm::normalize(glm::dvec3(0.55, 0.45, 0.7));
    const double r = glm::length(base.box_max - base.box_min) * 0.5;
    for (const auto& [view, dist, fov] : {std::tuple{"close", 1.05 * r, 60.0}, std::tuple{"far", 3.0 * r, 30.0}}) {
      nlohmann::json cam = {{"eye", {c.x + dist * dir.x, c.y + dist * dir.y, c.z + dist * dir.z}},
                            {"center", {c.x, c.y, c.z}},
                            {"up", {0, 1, 0}},
                            {"fov_y", fov}};
      nlohmann::json jv = j;
      jv["camera"] = cam;
      const SamplingView v{caster, a, *vol, gv, view, jv};
      time_sampling_methods(v);
      time_interactive(v);
    }
  }
  std::printf(
      "spr: samples (filter evaluations) per ray; PSNR against the converged DVR image (CPU, double) of the same "
      "scene and filter\n");
  return 0;
}

}  // namespace

void add_sampling_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<SamplingBenchArgs>();
  auto* s = bench.add_subcommand("sampling",
                                 "Knoll Table 2 style: uniform vs differential (and adaptive) sampling, "
                                 "frame time and PSNR against the converged image, close and far views");
  s->add_option("volumes", a->volumes, "volume files")->required();
  s->add_option("--size", a->size, "square image size");
  s->add_option("--frames", a->frames, "timed frames per case (after one warm-up)");
  s->callback([a, &run] { run = [a] { return run_sampling_bench(*a); }; });
}

}  // namespace peakcast::bench
