// `peakcast-bench raycast` and `peaks`: frame time and sampling throughput of the GL ray caster against a bare
// sampling loop (same rays, same per-ray sample counts, reconstruction only), measured in the
// same run. A benchmark command, not a test: the em volume alone is 837 MB.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include <glm/geometric.hpp>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "core/generators.h"
#include "core/volume_io.h"
#include "core/peaks.h"
#include "core/preintegration.h"
#include "reference/reference_renderer.h"
#include "reference/metrics.h"
#include "render/backend.h"

namespace fs = std::filesystem;

namespace peakcast::bench {
namespace {

struct BenchArgs {
  std::vector<std::string> volumes{"blobs", "marschner-lobb", "em"};
  std::vector<int> sizes{512, 1024};
  std::vector<std::string> paths{"fragment", "compute"};
  int frames = 5;
  std::string data_dir = "bench-data";
};

struct PeaksArgs {
  std::string volume;
  int size = 512;
  int frames = 3;
};

struct BenchVolume {
  std::string name;
  GeneratorSpec spec;
};

BenchVolume raycast_volume(const std::string& name) {
  GeneratorSpec s;
  s.kind = parse_generator_kind(name);
  s.type = default_type(s.kind);
  if (s.kind == GeneratorKind::Blobs)
    s.dims = {256, 256, 256};
  else if (s.kind == GeneratorKind::MarschnerLobb)
    s.dims = {128, 128, 128};
  else if (s.kind == GeneratorKind::Em)
    s.dims = {900, 500, 930};
  else
    s.dims = {256, 256, 256};
  std::ostringstream n;
  n << name << "_" << s.dims[0] << "x" << s.dims[1] << "x" << s.dims[2];
  return {n.str(), s};
}

// Generated once into the data directory and reused by later runs.
std::shared_ptr<Volume> load_or_make(const BenchVolume& bv, const fs::path& dir) {
  fs::create_directories(dir);
  const fs::path file = dir / (bv.name + ".raw");
  if (!fs::exists(file)) {
    std::printf("generating %s ...\n", file.c_str());
    std::fflush(stdout);
    generate_to_file(bv.spec, file);
  }
  return std::make_shared<Volume>(load_volume(file));
}

// The raycast scene of a volume at one image size: bench_scene's ramp TF and three-quarter view.
ResolvedScene raycast_scene(const Volume& vol, int size) { return bench_scene(vol, size, "trilinear"); }

// `raycast`: every volume, size and path, the full ray caster against the bare sampling loop.
int run_raycast(const BenchArgs& a) {
  BenchRenderer b = make_bench_renderer();
  render::Renderer& caster = *b.renderer;
  std::printf("%-22s %5s %-5s %-30s %9s %8s %10s | %9s %10s | %6s\n", "volume", "size", "path", "variant", "median_ms",
              "spr", "Msamples/s", "bare_ms", "bare_MS/s", "ratio");
  for (const auto& name : a.volumes) {
    const BenchVolume bv = raycast_volume(name);
    auto vol = load_or_make(bv, a.data_dir);
    auto resident = caster.make_resident(vol);
    const render::ResidentVolume& gv = *resident;
    for (int size : a.sizes) {
      const ResolvedScene s = raycast_scene(*vol, size);
      for (const auto& p : a.paths) {
        const auto path = p == "compute" ? render::RenderPath::Compute : render::RenderPath::Fragment;
        std::vector<double> full_ms, bare_ms;
        render::RenderStats st, bst;
        Image img;
        for (int f = 0; f <= a.frames; ++f) {
          img = caster.render(gv, s, path, &st);
          b.bench->render_bare(gv, s, path, img, &bst);
          if (f > 0) {  // frame 0 warms up (shader compile, first upload)
            full_ms.push_back(st.render_ms);
            bare_ms.push_back(bst.render_ms);
          }
        }
        const double fm = median(full_ms), bm = median(bare_ms);
        const double rate = st.samples_total / (fm / 1000.0) / 1e6, brate = bst.samples_total / (bm / 1000.0) / 1e6;
        std::printf("%-22s %5d %-5s %-30s %9.1f %8.1f %10.1f | %9.1f %10.1f | %6.2f\n", bv.name.c_str(), size,
                    p == "compute" ? "comp" : "frag", st.variant.c_str(), fm, st.samples_mean, rate, bm, brate,
                    fm / bm);
        std::fflush(stdout);
      }
    }
  }
  std::printf("spr: samples per ray (rays that hit the box); ratio: full frame ms / bare loop ms (same samples)\n");
  return 0;
}

// The `peaks` scene of the volume in `file`: Fig. 3's TF over its range, shaded at step 1, from a fixed oblique view.
nlohmann::json peaks_scene(const fs::path& file, const Volume& vol, int size) {
  // Fig. 3: a near-Dirac red peak (width 1e-4 of the range) and a smooth blue feature.
  const double lo = vol.min_value, span = vol.max_value - vol.min_value;
  auto x = [&](double r) { return lo + r * span; };
  nlohmann::json tf = {{"points",
                        {{x(0.0), 0.1, 0.3, 1.0, 0.0},
                         {x(0.15), 0.2, 0.5, 1.0, 0.0},
                         {x(0.35), 0.2, 0.5, 1.0, 0.04},
                         {x(0.55), 0.2, 0.5, 1.0, 0.0},
                         {x(0.78) - 1e-4 * span, 1.0, 0.1, 0.0, 0.0},
                         {x(0.78), 1.0, 0.1, 0.0, 0.9},
                         {x(0.78) + 1e-4 * span, 1.0, 0.1, 0.0, 0.0},
                         {x(1.0), 1.0, 1.0, 1.0, 0.0}}}};
  const glm::dvec3 c = vol.origin + vol.extent() * 0.5;
  const double dist = glm::length(vol.extent()) * 0.5 / std::sin(15.0 * M_PI / 180.0);
  const glm::dvec3 eye = c + dist * glm::normalize(glm::dvec3(0.0, -0.72, 1.0));
  return {{"volume", file.string()},
          {"image", {{"width", size}, {"height", size}}},
          {"tf", tf},
          {"camera", {{"eye", {eye.x, eye.y, eye.z}}, {"center", {c.x, c.y, c.z}}, {"up", {0, 0, 1}}}},
          {"render", {{"shading", true}, {"step", 1.0}}}};
}

// The build times of the peak tables and the preintegration tables over the volume's range.
void time_peak_tables(const std::vector<Peak>& peaks, const ResolvedScene& base, double lo, double span) {
  for (int bins : {128, 256, 1024}) {
    std::vector<double> ms;
    for (int k = 0; k < 5; ++k) ms.push_back(build_peak_table(peaks, lo, lo + span, bins).build_ms);
    std::printf("peak table %4d bins: %.2f ms (median of 5)\n", bins, median(ms));
  }
  for (auto method : {PreintegrationMethod::Exact, PreintegrationMethod::Integral})
    for (int size : {256, 512}) {
      std::vector<double> ms;
      for (int k = 0; k < 3; ++k)
        ms.push_back(build_preintegration(base.tf, lo, lo + span, base.step, size, method).build_ms);
      std::printf("preintegration table %d^2 (%s): %.1f ms (median of 3)\n", size,
                  method == PreintegrationMethod::Exact ? "exact" : "integral functions", median(ms));
    }
}

// `peaks`: the three classifications against the converged references, then the tables' build times.
int run_peaks(const PeaksArgs& pa) {
  const fs::path file =
      pa.volume.empty() ? fs::path(PEAKCAST_SOURCE_DIR) / "tests/data/heptane_151.nrrd" : fs::path(pa.volume);
  auto vol = std::make_shared<Volume>(load_volume(file));
  render::RenderBackend b = render::open_backend(render::requested_backend());
  std::printf("renderer: %s\n", b.description().c_str());
  std::printf("volume: %s\n", vol->to_string().c_str());
  render::Renderer& caster = *b.renderer;
  auto resident = caster.make_resident(vol);
  const render::ResidentVolume& gv = *resident;
  const double lo = vol->min_value, span = vol->max_value - vol->min_value;
  nlohmann::json j = peaks_scene(file, *vol, pa.size);
  std::printf("references (CPU, converged) ...\n");
  std::fflush(stdout);
  const ResolvedScene base = resolve_scene(parse_scene(j), *vol);
  const auto ref_peaks = reference::render_converged(*vol, base, reference::OpticalModel::Peaks, 1e-4, 1.0 / 16);
  const auto ref_dvr = reference::render_converged(*vol, base, reference::OpticalModel::Dvr, 1e-4, 1.0 / 16);
  std::printf("%-8s %9s %8s %14s %12s %12s\n", "method", "median_ms", "spr", "variant", "PSNR_peak", "PSNR_dvr");
  for (const char* method : {"peaks", "post", "preint"}) {
    j["render"]["classification"] = method;
    const ResolvedScene s = resolve_scene(parse_scene(j), *vol);
    std::vector<double> ms;
    render::RenderStats st;
    Image img;
    for (int f = 0; f <= pa.frames; ++f) {
      img = caster.render(gv, s, render::RenderPath::Fragment, &st);
      if (f > 0) ms.push_back(st.render_ms);
    }
    std::printf("%-8s %9.1f %8.1f %14s %12.1f %12.1f\n", method, median(ms), st.samples_mean, st.variant.c_str(),
                reference::compare(img, ref_peaks.image).psnr, reference::compare(img, ref_dvr.image).psnr);
  }
  time_peak_tables(find_peaks(resolve_scene(parse_scene(j), *vol).tf), base, lo, span);
  std::printf("references: peak model step %.4f (change %.1e), DVR step %.4f (change %.1e)\n", ref_peaks.step,
              ref_peaks.last_change, ref_dvr.step, ref_dvr.last_change);
  return 0;
}

// Registers `raycast` and its options.
void add_raycast_command(CLI::App* bench, Runner& run) {
  auto a = std::make_shared<BenchArgs>();
  auto* rc =
      bench->add_subcommand("raycast", "GL ray caster vs a bare sampling loop: blobs 256^3, ML 128^3, em 900x500x930");
  rc->add_option("--volumes", a->volumes, "generator kinds (blobs, marschner-lobb, em, fire)")->delimiter(',');
  rc->add_option("--sizes", a->sizes, "square image sizes")->delimiter(',');
  rc->add_option("--paths", a->paths, "fragment, compute")->delimiter(',');
  rc->add_option("--frames", a->frames, "timed frames per case (after one warm-up)");
  rc->add_option("--data-dir", a->data_dir, "where generated volumes are cached");
  rc->callback([a, &run] { run = [a] { return run_raycast(*a); }; });
}

// Registers `peaks` and its options.
void add_peaks_command(CLI::App* bench, Runner& run) {
  auto pa = std::make_shared<PeaksArgs>();
  auto* pk =
      bench->add_subcommand("peaks", "Knoll Table 1 / Fig. 3: peak finding vs postclassification vs preintegration");
  pk->add_option("--volume", pa->volume, "volume file (default: the heptane sample)");
  pk->add_option("--size", pa->size, "square image size");
  pk->add_option("--frames", pa->frames, "timed frames per method");
  pk->callback([pa, &run] { run = [pa] { return run_peaks(*pa); }; });
}

}  // namespace

void add_raycast_peaks_commands(CLI::App& app, Runner& run) {
  CLI::App* bench = &app;
  add_raycast_command(bench, run);
  add_peaks_command(bench, run);
}

}  // namespace peakcast::bench
