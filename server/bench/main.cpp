// peakcast-bench: the benchmarks, commands that measure (never tests). Same libraries as the
// `peakcast` executable, kept out of it so the product binary holds only the product.
// `peakcast-bench --help` lists them.
#include "bench/commands.h"

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
  peakcast::bench::add_stream_command(app, run);
  peakcast::bench::add_outofcore_command(app, run);
  peakcast::bench::add_raytex_command(app, run);
  peakcast::bench::add_quality_command(app, run);
  peakcast::bench::add_scene_command(app, run);
  return peakcast::app::run_command_line(app, run, argc, argv, "peakcast-bench");
}
