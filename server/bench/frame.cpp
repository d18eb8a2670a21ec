// `bench readback`: a streamed frame's cost on the render thread with the float read-back and
// CPU row flip it used to have, against the 8-bit read-back, all in one run.
// `bench volume-switch`: the render thread's stall when a session switches to a freshly loaded
// volume, with the macrocell grids built there or handed over from the loader.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "core/generators.h"
#include "core/volume_io.h"
#include "encode/png.h"
#include "render/backend.h"

namespace peakcast::bench {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct ReadbackArgs {
  std::string volume = "blobs";
  std::vector<int> sizes{512, 1024};
  std::vector<std::string> paths{"fragment"};
  int frames = 7;
};

struct SwitchArgs {
  std::string volume;
  int size = 512;
  int repeats = 2;
};

// One way to produce a streamed frame's pixels.
struct Case {
  const char* name;
  render::RenderOutput output;
  bool samples;      // Rgb8: read the sample counts too
  bool legacy_flip;  // what draw() did before: read into scratch buffers, flip rows into an Image
};

void run_readback(const ReadbackArgs& a) {
  BenchRenderer gl = make_bench_renderer();
  render::Renderer& caster = *gl.renderer;
  auto vol = bench_volume(a.volume);
  auto resident = caster.make_resident(vol);
  const render::ResidentVolume& gv = *resident;
  std::printf("volume: %s\n", vol->to_string().c_str());
  const Case cases[] = {{"float20+flip (before)", render::RenderOutput::Float, true, true},
                        {"float20", render::RenderOutput::Float, true, false},
                        {"rgb8+samples", render::RenderOutput::Rgb8, true, false},
                        {"rgb8", render::RenderOutput::Rgb8, false, false}};
  std::printf("%5s %-5s %-22s %9s %9s %11s %9s %11s %8s\n", "size", "path", "output", "frame_ms", "render_ms",
              "readback_ms", "flip_ms", "to_rgb8_ms", "ratio");
  for (int size : a.sizes)
    for (const auto& p : a.paths) {
      const ResolvedScene s = bench_scene(*vol, size, "trilinear");
      render::RenderRequest req;
      req.path = p == "compute" ? render::RenderPath::Compute : render::RenderPath::Fragment;
      const size_t n = std::size(cases);
      std::vector<std::vector<double>> frame(n), rend(n), rb(n), flip(n), conv(n);
      // Cases take turns within each round so drift (other jobs on the machine) hits all alike.
      for (int f = 0; f <= a.frames; ++f)
        for (size_t c = 0; c < n; ++c) {
          req.output = cases[c].output;
          req.sample_stats = cases[c].samples;
          render::RenderStats st;
          const auto t0 = Clock::now();
          render::RenderResult r = caster.render(gv, s, req, &st);
          double flip_ms = 0.0;
          if (cases[c].legacy_flip) {
            const auto t1 = Clock::now();
            Image img(size, size);
            const Image& src = r.image;
            for (int y = 0; y < size; ++y) {
              std::copy_n(src.pixel(0, size - 1 - y), size_t(size) * 4, img.pixel(0, y));
              std::copy_n(&src.samples[size_t(size - 1 - y) * size], size_t(size), &img.samples[size_t(y) * size]);
            }
            flip_ms = ms_since(t1);
          }
          const double frame_ms = ms_since(t0);
          double conv_ms = 0.0;
          if (cases[c].output == render::RenderOutput::Float) {  // the encode pool's job, not the render thread's
            const auto t2 = Clock::now();
            const auto rgb = encode::to_rgb8(r.image);
            conv_ms = ms_since(t2);
          }
          if (f == 0) continue;  // warm-up: shader compile, first allocation of the targets
          frame[c].push_back(frame_ms);
          rend[c].push_back(st.render_ms);
          rb[c].push_back(st.readback_ms);
          flip[c].push_back(flip_ms);
          conv[c].push_back(conv_ms);
        }
      const double before = median(frame[0]);
      for (size_t c = 0; c < n; ++c)
        std::printf("%5d %-5s %-22s %9.2f %9.2f %11.2f %9.2f %11.2f %8.3f\n", size, p == "compute" ? "comp" : "frag",
                    cases[c].name, median(frame[c]), median(rend[c]), median(rb[c]), median(flip[c]), median(conv[c]),
                    median(frame[c]) / before);
      std::fflush(stdout);
    }
  std::printf(
      "medians of %d frames; frame_ms: the render thread's time per frame (render call + flip); ratio: "
      "frame_ms / frame_ms of 'float20+flip (before)'; to_rgb8_ms: CPU conversion the float cases leave to "
      "the encode pool\n",
      a.frames);
}

void run_switch(const SwitchArgs& a) {
  BenchRenderer gl = make_bench_renderer();
  render::Renderer& caster = *gl.renderer;
  const auto t_load = Clock::now();
  auto vol = std::make_shared<Volume>(load_volume(a.volume));
  std::printf("volume: %s, loaded in %.0f ms\n", vol->to_string().c_str(), ms_since(t_load));
  const ResolvedScene lin = bench_scene(*vol, a.size, "trilinear"), cub = bench_scene(*vol, a.size, "tricubic");
  {  // warm-up: compile both variants so no measured frame includes a shader compile
    auto warm_resident = caster.make_resident(vol);
    const render::ResidentVolume& warm = *warm_resident;
    caster.render(warm, lin, render::RenderPath::Fragment);
    caster.render(warm, cub, render::RenderPath::Fragment);
  }
  std::printf("%-28s %9s %10s %13s %14s %15s %14s\n", "macrocells", "loader_ms", "upload_ms", "render_cells",
              "first_frame_ms", "first_cubic_ms", "stall_ms");
  for (int rep = 0; rep < a.repeats; ++rep)
    for (bool prebuilt : {false, true}) {
      VolumeMacrocells cells;
      double loader_ms = 0.0;
      if (prebuilt) {  // what VolumeStore::add does on the loader pool
        cells = build_volume_macrocells(*vol);
        loader_ms = cells.build_ms;
      }
      // From here on: the render thread.
      const auto t0 = Clock::now();
      auto resident = caster.make_resident(vol, cells);
      const render::ResidentVolume& gv = *resident;
      const auto t1 = Clock::now();
      render::RenderStats st;
      caster.render(gv, lin, render::RenderPath::Fragment, &st);
      const double first = ms_since(t1);
      const auto t2 = Clock::now();
      caster.render(gv, cub, render::RenderPath::Fragment);
      const double first_cubic = ms_since(t2);
      const double stall = ms_since(t0);
      std::printf("%-28s %9.0f %10.0f %13.0f %14.0f %15.0f %14.0f   (first frame: GPU %.0f ms, tables %.0f ms)\n",
                  prebuilt ? "loader pool (after)" : "render thread (before)", loader_ms, gv.upload_ms(),
                  gv.macrocell_ms(), first, first_cubic, stall, st.render_ms, st.table_ms);
      std::fflush(stdout);
    }
  std::printf(
      "stall_ms: render-thread time from the resident volume's construction through the first trilinear and the first "
      "tricubic frame (%dx%d); render_cells: macrocell builds on the render thread; loader_ms: both grids "
      "built on the loader pool\n",
      a.size, a.size);
}

}  // namespace

void add_frame_commands(CLI::App& bench, Runner& run) {
  auto ra = std::make_shared<ReadbackArgs>();
  auto* rb = bench.add_subcommand("readback", "A streamed frame: float read-back + CPU flip (before) vs 8-bit RGB");
  rb->add_option("--volume", ra->volume, "volume file, or a generator kind made in memory (default blobs 256^3)");
  rb->add_option("--sizes", ra->sizes, "square image sizes")->delimiter(',');
  rb->add_option("--paths", ra->paths, "fragment, compute")
      ->delimiter(',')
      ->check(CLI::IsMember({"fragment", "compute"}));
  rb->add_option("--frames", ra->frames, "timed frames per case (after one warm-up)")->check(CLI::Range(1, 1000));
  rb->callback([ra, &run] {
    run = [ra] {
      run_readback(*ra);
      return 0;
    };
  });
  auto sa = std::make_shared<SwitchArgs>();
  auto* sw = bench.add_subcommand("volume-switch",
                                  "Render-thread stall switching to a fresh volume: macrocells built "
                                  "there vs on the loader pool");
  sw->add_option("volume", sa->volume, "volume file (e.g. make-volume em -o em.nrrd)")
      ->required()
      ->check(CLI::ExistingFile);
  sw->add_option("--size", sa->size, "square image size")->check(CLI::Range(16, 4096));
  sw->add_option("--repeats", sa->repeats, "measurements of each")->check(CLI::Range(1, 20));
  sw->callback([sa, &run] {
    run = [sa] {
      run_switch(*sa);
      return 0;
    };
  });
}

}  // namespace peakcast::bench
