// Sub-commands of the `peakcast` executable; each registers itself on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace peakcast::app {

// A command's body runs after parsing and returns the process exit code.
using Runner = std::function<int()>;

void add_volume_commands(CLI::App& app, Runner& run);  // make-volume, convert, info
void add_render_commands(CLI::App& app, Runner& run);  // render, reference, compare
void add_bench_commands(CLI::App& app, Runner& run);   // bench raycast, bench peaks
void add_serve_command(CLI::App& app, Runner& run);    // serve
void add_bench_serve_command(CLI::App& bench, Runner& run);  // bench serve
void add_bench_soak_command(CLI::App& bench, Runner& run);   // bench soak
void add_bench_sampling_command(CLI::App& bench, Runner& run);  // bench sampling
void add_bench_frame_commands(CLI::App& bench, Runner& run);  // bench readback, bench volume-switch
void add_bench_raytex_command(CLI::App& bench, Runner& run);  // bench raytex
void add_bench_quality_command(CLI::App& bench, Runner& run);  // bench quality
void add_bench_scene_command(CLI::App& bench, Runner& run);  // bench scene

// Exit codes: 0 ok, 1 failure of the job (GL, EGL, shader, I/O while writing), 2 bad input
// (file, scene, arguments).
constexpr int kExitFailure = 1;
constexpr int kExitBadInput = 2;

}  // namespace peakcast::app
