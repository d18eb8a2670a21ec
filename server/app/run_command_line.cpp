#include <cstdio>
#include <exception>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "core/scene.h"
#include "core/volume_io.h"

namespace peakcast::app {

int run_command_line(CLI::App& app, Runner& run, int argc, char** argv, const char* program) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; a refused argument exits 2 like any other bad input.
    const int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }
  auto fail = [program](const std::exception& e, int code) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return code;
  };
  try {
    return run ? run() : 0;
  } catch (const VolumeError& e) {
    return fail(e, kExitBadInput);
  } catch (const SceneError& e) {
    return fail(e, kExitBadInput);
  } catch (const nlohmann::json::exception& e) {
    return fail(e, kExitBadInput);
  } catch (const std::invalid_argument& e) {
    return fail(e, kExitBadInput);
  } catch (const std::exception& e) {  // GL, EGL, shaders, writing output
    return fail(e, kExitFailure);
  }
}

}  // namespace peakcast::app
