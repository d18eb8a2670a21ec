// Sub-commands of `peakcast-bench`, the benchmarks (commands, never tests); each registers
// itself on the CLI11 app. They share the product's libraries and its exit codes.
#pragma once

#include <CLI/CLI.hpp>

#include "app/commands.h"

namespace peakcast::bench {

using app::kExitBadInput;
using app::kExitFailure;
using app::Runner;

void add_raycast_peaks_commands(CLI::App& app, Runner& run);  // raycast, peaks
void add_serve_command(CLI::App& app, Runner& run);           // serve
void add_soak_command(CLI::App& app, Runner& run);            // soak
void add_sampling_command(CLI::App& app, Runner& run);        // sampling
void add_frame_commands(CLI::App& app, Runner& run);          // readback, volume-switch
void add_raytex_command(CLI::App& app, Runner& run);          // raytex
void add_quality_command(CLI::App& app, Runner& run);         // quality
void add_scene_command(CLI::App& app, Runner& run);           // scene
void add_stream_command(CLI::App& app, Runner& run);          // stream
void add_outofcore_command(CLI::App& app, Runner& run);       // outofcore

}  // namespace peakcast::bench
