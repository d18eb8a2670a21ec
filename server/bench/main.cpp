// peakcast-bench: the benchmarks, commands that measure (never tests). Same libraries as the
// `peakcast` executable, kept out of it so the product binary holds only the product.
// `peakcast-bench --help` lists them.
#include <cstdio>
#include <exception>

#include "bench/commands.h"
#include "core/scene.h"
#include "core/volume_io.h"

int main(int argc, char** argv) {
  CLI::App app{"peakcast-bench " PEAKCAST_VERSION " - benchmarks of the peakcast ray caster and render server"};
  app.set_version_flag("--version", "peakcast-bench " PEAKCAST_VERSION);
  app.require_subcommand(1);
  peakcast::bench::Runner run;
  peakcast::bench::add_raycast_peaks_commands(app, run);
  peakcast::bench::add_serve_command(app, run);
  peakcast::bench::add_soak_command(app, run);
  peakcast::bench::add_sampling_command(app, run);
  peakcast::bench::add_frame_commands(app, run);
  peakcast::bench::add_raytex_command(app, run);
  peakcast::bench::add_quality_command(app, run);
  peakcast::bench::add_scene_command(app, run);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : peakcast::bench::kExitBadInput;
  }
  auto fail = [](const std::exception& e, int code) {
    std::fprintf(stderr, "peakcast-bench: error: %s\n", e.what());
    return code;
  };
  try {
    return run ? run() : 0;
  } catch (const peakcast::VolumeError& e) {
    return fail(e, peakcast::bench::kExitBadInput);
  } catch (const peakcast::SceneError& e) {
    return fail(e, peakcast::bench::kExitBadInput);
  } catch (const std::invalid_argument& e) {
    return fail(e, peakcast::bench::kExitBadInput);
  } catch (const std::exception& e) {
    return fail(e, peakcast::bench::kExitFailure);
  }
}
