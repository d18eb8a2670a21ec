// Sub-commands of the `peakcast` executable; each registers itself on the CLI11 app. The
// benchmarks are another executable's (bench/commands.h).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace peakcast::app {

// A command's body runs after parsing and returns the process exit code.
using Runner = std::function<int()>;

void add_volume_commands(CLI::App& app, Runner& run);  // make-volume, convert, info
void add_render_commands(CLI::App& app, Runner& run);  // render, reference, compare
void add_serve_command(CLI::App& app, Runner& run);    // serve

// Parses the command line and runs the chosen command; a failure is one line on stderr,
// "<program>: error: ...", and the exit code below.
int run_command_line(CLI::App& app, Runner& run, int argc, char** argv, const char* program);

// Exit codes: 0 ok, 1 failure of the job (GL, EGL, shader, I/O while writing), 2 bad input
// (file, scene, arguments).
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;

}  // namespace peakcast::app
