// peakcast: remote volume visualisation. `peakcast --help` lists the sub-commands.
#include <cstdio>
#include <exception>

#include "app/commands.h"
#include "core/scene.h"
#include "core/volume_io.h"

int main(int argc, char** argv) {
  CLI::App app{"peakcast " PEAKCAST_VERSION " - peak-finding volume ray caster and render server"};
  app.set_version_flag("--version", "peakcast " PEAKCAST_VERSION);
  app.require_subcommand(1);
  peakcast::app::Runner run;
  peakcast::app::add_volume_commands(app, run);
  peakcast::app::add_render_commands(app, run);
  peakcast::app::add_serve_command(app, run);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; a refused argument exits 2 like any other bad input.
    const int code = app.exit(e);
    return code == 0 ? 0 : peakcast::app::kExitBadInput;
  }
  auto fail = [](const std::exception& e, int code) {
    std::fprintf(stderr, "peakcast: error: %s\n", e.what());
    return code;
  };
  try {
    return run ? run() : 0;
  } catch (const peakcast::VolumeError& e) {
    return fail(e, peakcast::app::kExitBadInput);
  } catch (const peakcast::SceneError& e) {
    return fail(e, peakcast::app::kExitBadInput);
  } catch (const nlohmann::json::exception& e) {
    return fail(e, peakcast::app::kExitBadInput);
  } catch (const std::invalid_argument& e) {
    return fail(e, peakcast::app::kExitBadInput);
  } catch (const std::exception& e) {  // GL, EGL, shaders, writing output
    return fail(e, peakcast::app::kExitFailure);
  }
}
