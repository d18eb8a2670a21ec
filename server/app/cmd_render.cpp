// `render`, `reference` and `compare`.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/cmd_render_mpi.h"
#include "app/commands.h"
#include "app/scene_file.h"
#include "core/volume_io.h"
#include "distributed/brick_sequence.h"
#include "encode/png.h"
#include "reference/reference_renderer.h"
#include "reference/metrics.h"
#include "render/backend.h"

namespace peakcast::app {
namespace {

struct RenderArgs {
  std::string scene, out, stats, path = "fragment", backend, program_cache;
  int64_t memory_budget_mib = 0;  // 0: no budget, the volume is read whole
};

struct ReferenceArgs {
  std::string scene, out;
  double step = 0;
  bool converged = false;
  std::string model;
};

struct CompareArgs {
  std::string a, b;
};

// `render --memory-budget-mib`: a volume whose voxels exceed the budget, drawn by bricks
// (distributed/brick_sequence.h). -1 when it fits: the caller reads it whole.
int render_within_budget(const RenderArgs& a) {
  const ParsedSceneFile parsed = parse_scene_file(a.scene);
  const int64_t budget = a.memory_budget_mib << 20;
  LoadOptions one;
  one.region = VoxelRegion{{0, 0, 0}, {1, 1, 1}};
  const Volume head = load_volume(parsed.volume, one);
  const Dims& d = head.source_dims;
  const int64_t bytes = d[0] * d[1] * d[2] * int64_t(voxel_bytes(head.type()));
  if (bytes <= budget) return -1;
  const auto t0 = std::chrono::steady_clock::now();
  LoadOptions select;
  select.time_point = parsed.scene.time;
  const auto stats = distributed::sequence_statistics(parsed.volume.string(), select, budget);
  const ResolvedScene scene = resolve_scene(parsed.scene, stats.box);
  render::RenderBackend b = render::open_backend(render::requested_backend(a.backend), "", {}, a.program_cache);
  const auto r = distributed::render_sequence(*b.renderer, parsed.volume.string(), select, stats, scene, budget);
  encode::write_png(r.image, a.out);
  if (stats.budget_too_small)
    std::fprintf(stderr,
                 "warning: a memory budget of %lld MiB is too small for the statistics' grids and value counts "
                 "beside a brick: they held more than the budget; raise --memory-budget-mib\n",
                 (long long)a.memory_budget_mib);
  if (r.budget_too_small)
    std::fprintf(stderr,
                 "warning: a memory budget of %lld MiB is too small for the %dx%d image's buffers and the grids "
                 "(%.1f MiB) beside two bricks: the still held more than the budget; raise --memory-budget-mib\n",
                 (long long)a.memory_budget_mib, r.image.width, r.image.height, double(r.beside_bytes) / 1048576.0);
  const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "wrote %s: %dx%d by %d bricks in %d band%s (ghost %d, largest %.1f MiB; budget %lld MiB for %.1f MiB of "
      "voxels), statistics %.0f ms, read %.0f ms, render %.0f ms, wall %.0f ms, %s\n",
      a.out.c_str(), r.image.width, r.image.height, r.bricks, r.tiles, r.tiles == 1 ? "" : "s", r.ghost,
      double(r.largest_brick_bytes) / 1048576.0, (long long)a.memory_budget_mib, double(bytes) / 1048576.0, stats.ms,
      r.read_ms, r.render_ms, wall, b.description().c_str());
  if (!a.stats.empty()) {
    const nlohmann::json j = {{"bricks", r.bricks},
                              {"ghost", r.ghost},
                              {"tiles", r.tiles},
                              {"largest_brick_bytes", r.largest_brick_bytes},
                              {"statistics_bricks", stats.bricks},
                              {"bytes_read", stats.bytes_read + r.bytes_read},
                              {"statistics_ms", stats.ms},
                              {"read_ms", r.read_ms},
                              {"render_ms", r.render_ms},
                              {"wall_ms", wall},
                              {"budget_too_small", stats.budget_too_small || r.budget_too_small},
                              {"backend", render::to_string(b.backend)},
                              {"renderer", b.renderer->description()}};
    std::ofstream(a.stats) << j.dump(2) << "\n";
  }
  return 0;
}

// Writes render's --stats file: the render's stats, the TF it derived, and the backend that drew it.
void write_render_stats(const std::string& path, const LoadedScene& ls, const render::RenderBackend& b,
                        const render::RenderStats& st) {
  // The render keys are the stream's stats keys (RenderStats::to_json); the backend's are the CLI's.
  nlohmann::json j = st.to_json();
  if (ls.scene.tf_derived) {  // the TF it derived, to start editing from
    Scene with_tf;
    with_tf.tf = ls.scene.tf;
    with_tf.opacity_unit = ls.scene.tf.opacity_unit;
    j["tf"] = scene_to_json(with_tf)["tf"];
  }
  j["backend"] = render::to_string(b.backend);
  j["renderer"] = b.renderer->description();
  if (b.device) {
    j["gl_renderer"] = b.device->info().renderer;
    j["gl_version"] = b.device->info().version;
    j["egl_platform"] = b.device->info().platform;
  }
  std::ofstream(path) << j.dump(2) << "\n";
}

// Renders the scene render names: one brick per rank under mpirun, by bricks within a memory budget, else whole.
int run_render(const RenderArgs& ra) {
  if (mpi_world_size_hint() > 1) {  // under mpirun -np N (N > 1): one brick per rank
#ifdef PEAKCAST_HAVE_MPI
    return mpi_render(MpiRenderArgs{ra.scene, ra.out, ra.stats, ra.backend});
#else
    throw std::invalid_argument(
        "launched by mpirun with several ranks, but this peakcast was built without MPI "
        "(install libopenmpi-dev and paraview-dev, rebuild with PEAKCAST_WITH_MPI=ON)");
#endif
  }
  if (ra.memory_budget_mib > 0) {
    const int code = render_within_budget(ra);
    if (code >= 0) return code;  // -1: the volume fits the budget, read whole as usual
  }
  LoadedScene ls = load_scene_file(ra.scene);
  render::RenderBackend b = render::open_backend(render::requested_backend(ra.backend), "", {}, ra.program_cache);
  auto gv = b.renderer->make_resident(ls.volume);
  render::RenderStats st;
  const auto path = ra.path == "compute" ? render::RenderPath::Compute : render::RenderPath::Fragment;
  Image img = b.renderer->render(*gv, ls.scene, path, &st);
  encode::write_png(img, ra.out);
  std::printf("wrote %s: %dx%d, %s, %s\n", ra.out.c_str(), img.width, img.height, st.to_string().c_str(),
              b.description().c_str());
  for (const std::string& w : st.warnings) std::fprintf(stderr, "peakcast: warning: %s\n", w.c_str());
  if (!ra.stats.empty()) write_render_stats(ra.stats, ls, b, st);
  return 0;
}

// Registers render.
void add_render_command(CLI::App& app, Runner& run) {
  auto ra = std::make_shared<RenderArgs>();
  auto* render = app.add_subcommand("render", "Render a scene file to a PNG (GL through EGL, or the CPU backend)");
  render->add_option("scene", ra->scene, "scene JSON (proto/scene.schema.json)")->required()->check(CLI::ExistingFile);
  render->add_option("-o,--out", ra->out, "output PNG")->required();
  render->add_option("--stats", ra->stats, "write render stats as JSON here");
  render->add_option("--path", ra->path, "fragment | compute (GL backend)")
      ->check(CLI::IsMember({"fragment", "compute"}));
  render->add_option("--backend", ra->backend, "auto | gl | cpu (default: PEAKCAST_BACKEND, else auto)")
      ->check(CLI::IsMember({"auto", "gl", "cpu"}));
  render->add_option("--program-cache", ra->program_cache,
                     "GL: where linked shader programs are kept between runs: auto | off | a folder "
                     "(default: PEAKCAST_PROGRAM_CACHE, else auto, ~/.cache/peakcast/programs)");
  render
      ->add_option("--memory-budget-mib", ra->memory_budget_mib,
                   "host memory for voxels: a volume larger than this is drawn by bricks, front to back, "
                   "read one after another (docs/chunked-volumes.md)")
      ->check(CLI::PositiveNumber);
  render->callback([ra, &run] { run = [ra] { return run_render(*ra); }; });
}

// Renders the scene reference names on the CPU, at a given step or converged, and writes the PNG.
int run_reference(const ReferenceArgs& fa) {
  LoadedScene ls = load_scene_file(fa.scene);
  const auto t0 = std::chrono::steady_clock::now();
  Image img;
  std::string how;
  if (fa.converged) {
    const bool peaks =
        fa.model.empty() ? ls.scene.scene.render.classification == Classification::Peaks : fa.model == "peaks";
    auto c = reference::render_converged(*ls.volume, ls.scene,
                                         peaks ? reference::OpticalModel::Peaks : reference::OpticalModel::Dvr);
    img = std::move(c.image);
    how = std::string(peaks ? "peak" : "DVR") + " model, converged=" + std::string(c.converged ? "yes" : "no") +
          " step " + std::to_string(c.step) + " last change " + std::to_string(c.last_change);
  } else {
    reference::ReferenceOptions opt;
    opt.step = fa.step;
    img = reference::render_reference(*ls.volume, ls.scene, opt);
    how = "step " + std::to_string(fa.step > 0 ? fa.step : ls.scene.step);
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  encode::write_png(img, fa.out);
  std::printf("wrote %s: %dx%d, %.0f ms, %s\n", fa.out.c_str(), img.width, img.height, ms, how.c_str());
  return 0;
}

// Registers reference.
void add_reference_command(CLI::App& app, Runner& run) {
  auto fa = std::make_shared<ReferenceArgs>();
  auto* ref = app.add_subcommand("reference", "Render a scene on the CPU in double precision (the reference)");
  ref->add_option("scene", fa->scene, "scene JSON")->required()->check(CLI::ExistingFile);
  ref->add_option("-o,--out", fa->out, "output PNG")->required();
  auto* step = ref->add_option("--step", fa->step, "sampling step in world units (default: the scene's)");
  ref->add_flag("--converged", fa->converged, "the optical model itself: refine until the image changes < 1e-4")
      ->excludes(step);
  ref->add_option("--model", fa->model, "with --converged: dvr | peaks (default: peaks for classification peaks)")
      ->check(CLI::IsMember({"dvr", "peaks"}));
  ref->callback([fa, &run] { run = [fa] { return run_reference(*fa); }; });
}

// Registers compare.
void add_compare_command(CLI::App& app, Runner& run) {
  auto ca = std::make_shared<CompareArgs>();
  auto* cmp = app.add_subcommand("compare", "Print RMSE, PSNR, max abs error and share of pixels off by > 1/255");
  cmp->add_option("a", ca->a, "image")->required()->check(CLI::ExistingFile);
  cmp->add_option("b", ca->b, "image")->required()->check(CLI::ExistingFile);
  cmp->callback([ca, &run] {
    run = [ca] {
      std::printf("%s\n", reference::compare(encode::read_png(ca->a), encode::read_png(ca->b)).to_json().c_str());
      return 0;
    };
  });
}

}  // namespace

int mpi_world_size_hint() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 1;
}

void add_render_commands(CLI::App& app, Runner& run) {
  add_render_command(app, run);
  add_reference_command(app, run);
  add_compare_command(app, run);
}

}  // namespace peakcast::app
