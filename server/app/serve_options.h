// `peakcast serve`'s options, each reachable three ways with one precedence rule:
//   command-line flag  >  PEAKCAST_* environment variable  >  config-file key  >  built-in default.
// The names follow one rule: flag --max-fps, variable PEAKCAST_MAX_FPS, key max-fps (TOML, the
// file named by --config / PEAKCAST_CONFIG). Repeatable options take a list: the flag repeated,
// a comma-separated variable, a TOML array. `--print-config` prints the result as a config file,
// each line marked with where its value came from (the token is never printed).
#pragma once

#include <map>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "net/app_context.h"

namespace peakcast::app {

struct ServeOptions {
  net::ServerConfig server;
  std::vector<std::string> data, volumes;
  int idle_seconds = 0;
  int64_t gpu_budget_mib = 0;
  int64_t memory_budget_mib = 0;
  std::string web_dir, shader_dir;
  std::string upload_dir;
  int64_t max_upload_mib = limits::kDefaultMaxUploadBytes >> 20,
          upload_budget_mib = limits::kDefaultUploadBudgetBytes >> 20;
  int max_uploads = limits::kDefaultMaxConcurrentUploads;
  double uploads_per_minute = limits::kUploadsPerMinutePerClient;
  int upload_timeout = int(limits::kDefaultUploadIdleTimeout.count());
  double upload_min_rate_kib = limits::kDefaultUploadMinBytesPerSecond / 1024;
  int upload_deadline = int(limits::kDefaultUploadDeadline.count());
  std::string token_file, user_token_file;  // read by resolved()
  std::string log_level = "info", log_format = "text";
  std::string config_file;
  bool print_config = false;
  std::map<std::string, std::string> source;  // option key -> "flag" | "env NAME" | "file PATH" | "default"

  // server plus the fields kept here in other units, and the tokens read from their files.
  // Throws std::invalid_argument naming the option when a file cannot be read or is wrong.
  net::ServerConfig resolved() const;
};

// Adds every serve option to `cmd`, bound to `o`.
void add_serve_options(CLI::App& cmd, ServeOptions& o);

// After CLI11 has parsed the command line: fills what no flag gave from the environment, then the
// config file, and records each option's source. Throws std::invalid_argument naming the variable
// or file key when a value is refused, or a key in the file is not an option.
void apply_env_and_file(CLI::App& cmd, ServeOptions& o);

// The variable for an option key: "max-fps" -> "PEAKCAST_MAX_FPS".
std::string env_name(const std::string& key);

// The effective configuration as TOML, each value with its source in a comment.
std::string print_config(const CLI::App& cmd, const ServeOptions& o);

}  // namespace peakcast::app
