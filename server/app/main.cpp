// peakcast: remote volume visualisation. `peakcast --help` lists the sub-commands.
#include "app/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"peakcast " PEAKCAST_VERSION " - peak-finding volume ray caster and render server"};
  app.set_version_flag("--version", "peakcast " PEAKCAST_VERSION);
  app.require_subcommand(1);
  peakcast::app::Runner run;
  peakcast::app::add_volume_commands(app, run);
  peakcast::app::add_render_commands(app, run);
  peakcast::app::add_serve_command(app, run);
  return peakcast::app::run_command_line(app, run, argc, argv, "peakcast");
}
