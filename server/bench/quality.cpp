// `bench quality` (docs/accuracy.md): error against run time. For each scene (the standard ones in
// tests/bench/quality/, or --scene FILE), every applicable method over a sweep of steps (or
// s_k): median GPU frame time, samples per ray, and the error against the converged image of
// the method's own optical model; report.csv, report.md and one SVG per scene in --out, the
// observed convergence order per method, and what each piece of code the variant leaves out
// would cost if it ran. A benchmark command, not a test.
//
// A scene file is a scene (proto/scene.schema.json) whose volume is a path relative to the file,
// or "generate:KIND:WxHxD" for a procedural volume made in memory (core/generators.h).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <functional>
#include <sstream>
#include <thread>
#include <tuple>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "bench/quality_report.h"
#include "core/generators.h"
#include "core/peaks.h"
#include "core/sampling.h"
#include "core/volume_io.h"
#include "encode/png.h"
#include "reference/reference_renderer.h"
#include "reference/metrics.h"
#include "render/backend.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace peakcast::bench {
namespace {

struct QualityArgs {
  std::vector<std::string> scenes;
  std::string out;
  bool images = false;
  int frames = 3;
  double tolerance = 1e-4;
};

struct Method {
  std::string name;  // <classification>/<sampling>/<filter>[/vs3][/adaptive]
  json render;       // merged over the scene's render settings
  std::string knob;  // step | s_k
};

// The methods that apply to a scene: peak finding only for a TF with peaks, differential only
// for a perspective camera.
std::vector<Method> methods_for(const ResolvedScene& s) {
  const bool has_peaks = !find_peaks(s.tf).empty();
  std::vector<Method> m = {
      {"post/uniform/trilinear", {{"classification", "post"}}, "step"},
      {"preint/uniform/trilinear", {{"classification", "preint"}}, "step"},
      {"post/uniform/trilinear/adaptive", {{"classification", "post"}, {"adaptive", true}}, "step"},
      {"post/uniform/tricubic", {{"classification", "post"}, {"filter", "tricubic"}}, "step"},
      {"post/uniform/tricubic/vs3",
       {{"classification", "post"}, {"filter", "tricubic"}, {"virtual_samples", 3}},
       "step"},
  };
  if (!s.camera.orthographic)
    m.push_back({"post/differential/trilinear", {{"classification", "post"}, {"sampling", "differential"}}, "s_k"});
  if (has_peaks) {
    m.push_back({"peaks/uniform/trilinear", {{"classification", "peaks"}}, "step"});
    m.push_back({"peaks/uniform/tricubic/vs3",
                 {{"classification", "peaks"}, {"filter", "tricubic"}, {"virtual_samples", 3}},
                 "step"});
    if (!s.camera.orthographic)
      m.push_back({"peaks/differential/trilinear", {{"classification", "peaks"}, {"sampling", "differential"}}, "s_k"});
  }
  return m;
}

std::vector<fs::path> standard_scenes() {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(PEAKCAST_SOURCE_DIR) / "tests/bench/quality"))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

// "generate:KIND:WxHxD" or a path relative to the scene file; generated volumes are kept for
// the scenes after.
std::shared_ptr<Volume> scene_volume(const std::string& name, const fs::path& scene_file,
                                     std::map<std::string, std::shared_ptr<Volume>>& cache) {
  const bool generated = name.rfind("generate:", 0) == 0;
  const std::string key = generated ? name : fs::weakly_canonical(scene_file.parent_path() / name).string();
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  std::shared_ptr<Volume> v;
  if (generated) {
    const auto colon = name.find(':', 9);
    GeneratorSpec g;
    g.kind = parse_generator_kind(name.substr(9, colon - 9));
    g.type = default_type(g.kind);
    g.dims = default_dims(g.kind);
    if (colon != std::string::npos) {
      char x1 = 0, x2 = 0;
      std::istringstream in(name.substr(colon + 1));
      if (!(in >> g.dims[0] >> x1 >> g.dims[1] >> x2 >> g.dims[2]) || x1 != 'x' || x2 != 'x')
        throw SceneError(scene_file.string() + ": volume: expected generate:KIND:WxHxD, got " + name);
    }
    v = std::make_shared<Volume>(generate_volume(g));
    v->name = name.substr(9);
  } else {
    fs::path p = name;
    v = std::make_shared<Volume>(load_volume(p.is_relative() ? scene_file.parent_path() / p : p));
  }
  cache[key] = v;
  return v;
}

std::string machine_line(const render::RenderBackend& backend) {
  std::string cpu = "unknown CPU";
  std::ifstream in("/proc/cpuinfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  return "Machine: " + cpu + ", " + std::to_string(std::thread::hardware_concurrency()) +
         " cores; renderer: " + backend.description();
}

// What a run shares across its scenes: the arguments, the renderer, the output directory and
// what the report collects.
struct QualityRun {
  const QualityArgs& a;
  BenchRenderer& gl;
  const fs::path& out;
  std::vector<QualityRow> rows;
  std::vector<ConvergedTime> refs;
  std::vector<Omission> omissions;
};

// One scene while it is timed: its name and JSON, its volume (resident and resolved), and the
// converged references made for it so far.
struct QualityScene {
  const std::string& name;
  const json& base_json;
  const Volume& vol;
  const render::ResidentVolume& gv;
  const ResolvedScene& base;
  std::map<std::string, Image> conv;
};

// The converged reference of the scene for an optical model and filter, rendered on first use.
const Image& reference_for(QualityRun& q, QualityScene& s, bool peaks_model, const std::string& filter) {
  using Clock = std::chrono::steady_clock;
  const std::string key = std::string(peaks_model ? "peaks/" : "dvr/") + filter;
  if (auto it = s.conv.find(key); it != s.conv.end()) return it->second;
  json j = s.base_json;
  j["render"]["filter"] = filter;
  j["render"]["classification"] = peaks_model ? "peaks" : "post";
  const auto t0 = Clock::now();
  // The B-spline field costs 8 trilinear fetches a sample on the CPU too: its references
  // stop refining at 1/16 voxel (their last change is reported), the trilinear ones at 1/64.
  const auto c =
      reference::render_converged(s.vol, resolve_scene(parse_scene(j), s.vol),
                                  peaks_model ? reference::OpticalModel::Peaks : reference::OpticalModel::Dvr,
                                  q.a.tolerance, filter == "tricubic" ? 1.0 / 16 : 1.0 / 64);
  q.refs.push_back({s.name, key, ms_between(t0, Clock::now()), c.step, c.last_change});
  std::printf("  converged %s: %.0f ms, step %.4g, last change %.1e%s\n", key.c_str(), q.refs.back().ms, c.step,
              c.last_change, c.converged ? "" : " (NOT converged)");
  std::fflush(stdout);
  return s.conv.emplace(key, c.image).first->second;
}

// One method at one step (or s_k): its median frame ms, samples per ray and error, printed as a row.
QualityRow time_method_point(QualityRun& q, QualityScene& s, const Method& m, double k, bool tf_has_peaks) {
  const bool peaks_model = m.name.rfind("peaks/", 0) == 0;
  const std::string filter = m.render.value("filter", "trilinear");
  json j = s.base_json;
  // Every method key set, so a scene file's own sampling or filter never relabels a row.
  j["render"].update({{"sampling", "uniform"}, {"filter", "trilinear"}, {"virtual_samples", 0}, {"adaptive", false}});
  j["render"].update(m.render);
  if (m.knob == "s_k")
    j["render"]["s_k"] = k;
  else
    j["render"]["step"] = k * s.base.min_spacing;
  const ResolvedScene rs = resolve_scene(parse_scene(j), s.vol);
  std::vector<double> ms;
  render::RenderStats st;
  Image img;
  for (int f = 0; f <= q.a.frames; ++f) {
    img = q.gl.renderer->render(s.gv, rs, render::RenderPath::Fragment, &st);
    if (f > 0) ms.push_back(st.render_ms);
  }
  QualityRow r;
  r.scene = s.name;
  r.method = m.name;
  r.knob = m.knob;
  r.value = k;
  r.ms = median(ms);
  r.samples_per_ray = st.samples_mean;
  const auto e = reference::compare(img, reference_for(q, s, peaks_model, filter));
  r.rmse = e.rmse, r.psnr = e.psnr, r.max_abs = e.max_abs, r.share_off = e.share_off;
  if (tf_has_peaks) r.psnr_other = reference::compare(img, reference_for(q, s, !peaks_model, filter)).psnr;
  if (q.a.images) {
    fs::create_directories(q.out / "images");
    std::string n = s.name + "_" + m.name + "_" + m.knob + "_" + std::to_string(k);
    std::replace(n.begin(), n.end(), '/', '-');
    r.image = "images/" + n + ".png";
    encode::write_png(img, q.out / r.image);
  }
  std::printf("  %-34s %-4s %-6g %8.2f ms %7.1f spr %7.2f dB\n", m.name.c_str(), m.knob.c_str(), k, r.ms,
              r.samples_per_ray, r.psnr);
  std::fflush(stdout);
  return r;
}

// Every method that applies to the scene over its sweep of steps (or s_k), one row each.
void time_methods(QualityRun& q, QualityScene& s) {
  const bool tf_has_peaks = !find_peaks(s.base.tf).empty();
  // s_k counts pixel footprints at the focal distance: its sweep is the one that puts the
  // step there at the uniform sweep's 2, 1, 1/2, 1/4 voxels, so both cover the same range
  // whatever the image size and distance.
  double sk_one_voxel = 1.0;
  if (!s.base.camera.orthographic) {
    json j = s.base_json;
    j["render"]["sampling"] = "differential";
    j["render"]["s_k"] = 1.0;
    sk_one_voxel = s.base.min_spacing / plan_sampling(resolve_scene(parse_scene(j), s.vol)).footprint;
  }
  for (const Method& m : methods_for(s.base)) {
    std::vector<double> knobs = {2, 1, 0.5, 0.25};
    if (m.knob == "s_k")
      for (double& k : knobs) k *= sk_one_voxel;
    for (double k : knobs) q.rows.push_back(time_method_point(q, s, m, k, tf_has_peaks));
  }
}

// The median frame ms of a scene with the variant key changed by `f` (none: the variant chosen).
double time_with(QualityRun& q, const render::ResidentVolume& gv, const ResolvedScene& s,
                 std::function<void(render::VariantKey&)> f, render::RenderStats& st) {
  q.gl.bench->force_variant(std::move(f));
  std::vector<double> ms;
  for (int i = 0; i <= q.a.frames; ++i) {
    q.gl.renderer->render(gv, s, render::RenderPath::Fragment, &st);
    if (i > 0) ms.push_back(st.render_ms);
  }
  q.gl.bench->force_variant(nullptr);
  return median(ms);
}

// What the scene's variants leave out, put back and timed; one omission for each that differs.
void time_omissions(QualityRun& q, const QualityScene& sc) {
  // What the variant leaves out, put back (RendererSwitches::force_variant) and timed on the
  // scene's own settings at step 1: the macrocell loop when every cell is visible, peak
  // finding for a peak classification whose TF has no peaks.
  for (const auto& [what, settings, put_back] :
       {std::tuple<const char*, json, std::function<void(render::VariantKey&)>>{
            "macrocell loop (every cell visible)", json{{"classification", "post"}},
            [](render::VariantKey& k) { k.space_skipping = true; }},
        {"peak finding (TF without peaks)", json{{"classification", "peaks"}},
         [](render::VariantKey& k) { k.peaks = true; }}}) {
    json j = sc.base_json;
    j["render"].update(settings);
    const ResolvedScene s = resolve_scene(parse_scene(j), sc.vol);
    render::RenderStats chosen, full;
    const double chosen_ms = time_with(q, sc.gv, s, nullptr, chosen);
    const double full_ms = time_with(q, sc.gv, s, put_back, full);
    if (chosen.variant == full.variant) continue;  // the scene uses that code: nothing left out
    q.omissions.push_back({sc.name, what, chosen.variant, full.variant, chosen_ms, full_ms});
  }
}

// One scene file: its methods' rows, what its variants leave out, and its SVG plot.
void run_quality_scene(QualityRun& q, const fs::path& file, std::map<std::string, std::shared_ptr<Volume>>& volumes) {
  std::ifstream in(file);
  if (!in) throw SceneError(file.string() + ": cannot open scene file");
  std::stringstream text;
  text << in.rdbuf();
  const json base_json = json::parse(text.str());
  const std::string scene_name = file.stem().string();
  auto vol = scene_volume(base_json.value("volume", ""), file, volumes);
  auto resident = q.gl.renderer->make_resident(vol);
  const ResolvedScene base = resolve_scene(parse_scene(base_json), *vol);
  std::printf("scene %s: %s, %dx%d\n", scene_name.c_str(), vol->to_string().c_str(), base.scene.width,
              base.scene.height);
  std::fflush(stdout);
  // The converged references, one per optical model and filter the methods need.
  QualityScene s{scene_name, base_json, *vol, *resident, base, {}};
  time_methods(q, s);
  time_omissions(q, s);
  write_svg(q.out / (scene_name + ".svg"), scene_name, q.rows, q.refs);
}

int run_quality(const QualityArgs& a) {
  BenchRenderer gl = make_bench_renderer();
  const fs::path out = a.out;
  fs::create_directories(out);
  std::vector<fs::path> files;
  for (const auto& s : a.scenes) files.push_back(s);
  if (files.empty()) files = standard_scenes();
  QualityRun q{a, gl, out, {}, {}, {}};
  std::map<std::string, std::shared_ptr<Volume>> volumes;

  for (const auto& file : files) run_quality_scene(q, file, volumes);
  write_csv(out / "report.csv", q.rows);
  write_markdown(out / "report.md", q.rows, q.refs, q.omissions, machine_line(gl));
  std::printf("wrote %s/report.csv, report.md and %zu SVG plots\n", out.string().c_str(), files.size());
  return 0;
}

}  // namespace

void add_quality_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<QualityArgs>();
  auto* q = bench.add_subcommand("quality",
                                 "Error against run time per scene and method: report.csv, report.md and an "
                                 "SVG per scene (default: the standard scenes in tests/bench/quality)");
  q->add_option("--scene", a->scenes, "scene file (repeatable); volume relative to it, or generate:KIND:WxHxD")
      ->check(CLI::ExistingFile);
  q->add_option("--out", a->out, "output directory")->required();
  q->add_flag("--images", a->images, "write each rendered image as a PNG (the CSV names them)");
  q->add_option("--frames", a->frames, "timed frames per point (after one warm-up)")->check(CLI::Range(1, 100));
  q->add_option("--tolerance", a->tolerance, "the converged references' stopping change")
      ->check(CLI::Range(1e-7, 1e-2));
  q->callback([a, &run] { run = [a] { return run_quality(*a); }; });
}

}  // namespace peakcast::bench
