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
#include "encode/png.h"
#include "reference/cpu_raycaster.h"
#include "reference/metrics.h"
#include "render/backend.h"

namespace peakcast::app {
namespace {

struct RenderArgs {
  std::string scene, out, stats, path = "fragment", backend, program_cache;
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

}  // namespace

int mpi_world_size_hint() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 1;
}

void add_render_commands(CLI::App& app, Runner& run) {
  auto ra = std::make_shared<RenderArgs>();
  auto* render = app.add_subcommand("render", "Render a scene file to a PNG (GL through EGL, or the CPU backend)");
  render->add_option("scene", ra->scene, "scene JSON (proto/scene.schema.json)")->required()->check(CLI::ExistingFile);
  render->add_option("-o,--out", ra->out, "output PNG")->required();
  render->add_option("--stats", ra->stats, "write render stats as JSON here");
  render->add_option("--path", ra->path, "fragment | compute (GL backend)")->check(CLI::IsMember({"fragment", "compute"}));
  render->add_option("--backend", ra->backend, "auto | gl | cpu (default: PEAKCAST_BACKEND, else auto)")
      ->check(CLI::IsMember({"auto", "gl", "cpu"}));
  render->add_option("--program-cache", ra->program_cache,
                     "GL: where linked shader programs are kept between runs: auto | off | a folder "
                     "(default: PEAKCAST_PROGRAM_CACHE, else auto, ~/.cache/peakcast/programs)");
  render->callback([ra, &run] {
    run = [ra] {
      if (mpi_world_size_hint() > 1) {  // under mpirun -np N (N > 1): one brick per rank
#ifdef PEAKCAST_HAVE_MPI
        return mpi_render(MpiRenderArgs{ra->scene, ra->out, ra->stats, ra->backend});
#else
        throw std::invalid_argument("launched by mpirun with several ranks, but this peakcast was built without MPI "
                                    "(install libopenmpi-dev and paraview-dev, rebuild with PEAKCAST_WITH_MPI=ON)");
#endif
      }
      LoadedScene ls = load_scene_file(ra->scene);
      render::RenderBackend b = render::open_backend(render::requested_backend(ra->backend), "", {}, ra->program_cache);
      auto gv = b.renderer->make_resident(ls.volume);
      render::RenderStats st;
      const auto path = ra->path == "compute" ? render::GpuPath::Compute : render::GpuPath::Fragment;
      Image img = b.renderer->render(*gv, ls.scene, path, &st);
      encode::write_png(img, ra->out);
      std::printf("wrote %s: %dx%d, %s, %s\n", ra->out.c_str(), img.width, img.height, st.to_string().c_str(),
                  b.description().c_str());
      for (const std::string& w : st.warnings) std::fprintf(stderr, "peakcast: warning: %s\n", w.c_str());
      if (!ra->stats.empty()) {
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
        std::ofstream(ra->stats) << j.dump(2) << "\n";
      }
      return 0;
    };
  });

  auto fa = std::make_shared<ReferenceArgs>();
  auto* ref = app.add_subcommand("reference", "Render a scene on the CPU in double precision (the reference)");
  ref->add_option("scene", fa->scene, "scene JSON")->required()->check(CLI::ExistingFile);
  ref->add_option("-o,--out", fa->out, "output PNG")->required();
  auto* step = ref->add_option("--step", fa->step, "sampling step in world units (default: the scene's)");
  ref->add_flag("--converged", fa->converged, "the optical model itself: refine until the image changes < 1e-4")
      ->excludes(step);
  ref->add_option("--model", fa->model, "with --converged: dvr | peaks (default: peaks for classification peaks)")
      ->check(CLI::IsMember({"dvr", "peaks"}));
  ref->callback([fa, &run] {
    run = [fa] {
      LoadedScene ls = load_scene_file(fa->scene);
      const auto t0 = std::chrono::steady_clock::now();
      Image img;
      std::string how;
      if (fa->converged) {
        const bool peaks = fa->model.empty() ? ls.scene.scene.render.classification == Classification::Peaks
                                             : fa->model == "peaks";
        auto c = reference::render_converged(*ls.volume, ls.scene,
                                             peaks ? reference::OpticalModel::Peaks : reference::OpticalModel::Dvr);
        img = std::move(c.image);
        how = std::string(peaks ? "peak" : "DVR") + " model, converged=" + std::string(c.converged ? "yes" : "no") + " step " + std::to_string(c.step) +
              " last change " + std::to_string(c.last_change);
      } else {
        reference::ReferenceOptions opt;
        opt.step = fa->step;
        img = reference::render_reference(*ls.volume, ls.scene, opt);
        how = "step " + std::to_string(fa->step > 0 ? fa->step : ls.scene.step);
      }
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      encode::write_png(img, fa->out);
      std::printf("wrote %s: %dx%d, %.0f ms, %s\n", fa->out.c_str(), img.width, img.height, ms, how.c_str());
      return 0;
    };
  });

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

}  // namespace peakcast::app
