#include "app/serve_options.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdlib>
#include <set>
#include <sstream>
#include <stdexcept>

#include "render/backend.h"

namespace peakcast::app {
namespace {

// Options that are not settings: not layered, not printed.
const std::set<std::string> kNotSettings = {"help", "config", "print-config"};
// Repeatable options: a list in every form.
const std::set<std::string> kLists = {"data", "volume", "allow-origin", "allowed-host"};

std::string key_of(const CLI::Option& opt) { return opt.get_single_name(); }

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string part; std::getline(in, part, ',');)
    if (!part.empty()) out.push_back(part);
  return out;
}

// Sets an option the command line left alone; a refused value names where it came from.
void set_from(CLI::Option& opt, const std::vector<std::string>& values, const std::string& where) {
  try {
    for (const auto& v : values) opt.add_result(v);
    opt.run_callback();
  } catch (const CLI::Error& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
}

bool is_number(const std::string& s) {
  double d;
  auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
  return ec == std::errc() && end == s.data() + s.size() && !s.empty();
}

std::string toml_value(const std::string& s) {
  if (is_number(s)) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

// The options that say where settings come from: a config file, or printing them.
void add_config_options(CLI::App& s, ServeOptions& o) {
  s.add_option("--config", o.config_file, "read options from this TOML file (also PEAKCAST_CONFIG)");
  s.add_flag("--print-config", o.print_config, "print the effective configuration, each value's source, and exit");
}

// Where the server listens and which volumes it may open.
void add_network_options(CLI::App& s, ServeOptions& o) {
  net::ServerConfig& c = o.server;
  s.add_option("--bind", c.bind, "address to listen on (default loopback only)");
  s.add_option("--port", c.port, "TCP port (0: any free port)");
  s.add_option("--data", o.data, "directory volumes may be opened from (repeatable)");
  s.add_option("--volume", o.volumes, "volume to preload (repeatable; the first is the default view)");
}

// Who may connect: tokens, origins and host names.
void add_security_options(CLI::App& s, ServeOptions& o) {
  net::ServerConfig& c = o.server;
  s.add_option("--token", c.token,
               "require this bearer token (HTTP header, ?token= or hello.token); it shows in the process list: "
               "prefer --token-file");
  s.add_option("--token-file", o.token_file, "read the admin token from the first line of this file");
  s.add_option(
      "--user-token-file", o.user_token_file,
      "user tokens, a line \"NAME TOKEN\" each: they view, render and upload, and delete only their own uploads");
  s.add_option("--allow-origin", c.allow_origins, "WebSocket Origin to accept besides the server's own (repeatable)");
  s.add_option("--allowed-host", c.allowed_hosts,
               "a Host name to answer besides the bind address and localhost (repeatable; * for any): DNS rebinding");
}

// Caps on sessions, frame rates, memory and REST stills.
void add_limit_options(CLI::App& s, ServeOptions& o) {
  net::ServerConfig& c = o.server;
  s.add_option("--max-sessions", c.max_sessions, "concurrent WebSocket sessions")->check(CLI::Range(1, 4096));
  s.add_option("--idle-timeout", o.idle_seconds, "seconds without a client message before closing")
      ->check(CLI::Range(1, 86400));
  s.add_option("--max-fps", c.max_fps, "frames per second per session")->check(CLI::Range(1.0, 240.0));
  s.add_option("--max-kbps", c.max_kbps,
               "a video stream's bit-rate ceiling, kbit/s: what a session starts with and may not exceed")
      ->check(CLI::Range(limits::kMinKbps, limits::kMaxKbps));
  s.add_option("--gpu-budget-mib", o.gpu_budget_mib, "MiB of volume textures on the GPU")
      ->check(CLI::Range(int64_t(1), int64_t(1) << 24));
  s.add_option("--memory-budget-mib", o.memory_budget_mib,
               "MiB of host memory for one volume's voxels: a pyramid (OME-Zarr, Neuroglancer) opens at its "
               "finest level that fits, a larger volume of another format is refused; 0: no budget")
      ->check(CLI::Range(int64_t(0), int64_t(1) << 24));
  s.add_option("--preview-voxels", c.preview_voxels,
               "with --memory-budget-mib: a pyramid whose level within the budget has more voxels opens first at "
               "its finest level within this many (a first look), then at the level within the budget; 0: off")
      ->check(CLI::Range(int64_t(0), int64_t(1) << 40));
  s.add_option("--max-queued-stills", c.max_queued_stills,
               "REST stills waiting or rendering at once; beyond, 503 with Retry-After")
      ->check(CLI::Range(size_t(1), size_t(1024)));
  s.add_option("--max-still-samples", c.max_still_samples,
               "cost cap of one REST still: pixels x estimated samples per ray; beyond, 422")
      ->check(CLI::Range(1e3, 1e15));
  s.add_option("--still-band-samples", c.still_band_samples,
               "estimated samples per band of a still (bands alternate with viewers' frames)")
      ->check(CLI::Range(1e3, 1e12));
}

// Logging and thread counts.
void add_logging_and_thread_options(CLI::App& s, ServeOptions& o) {
  net::ServerConfig& c = o.server;
  s.add_option("--log-level", o.log_level, "debug | info | warn | error | off (stderr)")
      ->check(CLI::IsMember({"debug", "info", "warn", "error", "off"}));
  s.add_option("--log-format", o.log_format, "text | json (one JSON object per line)")
      ->check(CLI::IsMember({"text", "json"}));
  s.add_option("--io-threads", c.io_threads, "network threads")->check(CLI::Range(1, 64));
  s.add_option("--encode-threads", c.encode_threads, "JPEG encode threads")->check(CLI::Range(1, 64));
}

// Where uploads are kept and how large, how many and how fast they may be.
void add_upload_options(CLI::App& s, ServeOptions& o) {
  s.add_option(
      "--upload-dir", o.upload_dir,
      "where uploaded volumes are kept (POST /api/volumes); empty: uploads are off. Never inside a --data directory");
  s.add_option("--max-upload-mib", o.max_upload_mib, "MiB of one upload")
      ->check(CLI::Range(int64_t(1), int64_t(1) << 22));
  s.add_option("--upload-budget-mib", o.upload_budget_mib, "MiB of every upload kept, in all")
      ->check(CLI::Range(int64_t(1), int64_t(1) << 26));
  s.add_option("--max-uploads", o.max_uploads, "uploads received at once; beyond, 503")->check(CLI::Range(1, 64));
  s.add_option("--uploads-per-minute", o.uploads_per_minute,
               "uploads one client address may start a minute (a burst of 10); beyond, 429")
      ->check(CLI::Range(1.0, 1e6));
  s.add_option("--upload-timeout", o.upload_timeout, "seconds an upload may send nothing before it is ended")
      ->check(CLI::Range(1, 3600));
  s.add_option("--upload-min-rate-kib", o.upload_min_rate_kib,
               "KiB/s an upload must average after its first --upload-timeout seconds; slower, it is ended (408)")
      ->check(CLI::Range(0.0, 1e6));
  s.add_option("--upload-deadline", o.upload_deadline, "seconds within which an upload's whole body must arrive")
      ->check(CLI::Range(1, 86400));
}

// The client's and shaders' folders, and the GPU, program cache and backend that render.
void add_rendering_options(CLI::App& s, ServeOptions& o) {
  net::ServerConfig& c = o.server;
  s.add_option("--web-dir", o.web_dir, "the browser client's files");
  s.add_option("--shader-dir", o.shader_dir, "the GLSL shaders");
  s.add_option("--egl-device", c.egl_device,
               "auto (a GPU first, else software) | surfaceless | an EGL device index (one GPU per process)")
      ->check([](const std::string& v) {
        const bool index = !v.empty() && v.size() < 4 &&
                           std::all_of(v.begin(), v.end(), [](unsigned char ch) { return std::isdigit(ch) != 0; });
        return v == "auto" || v == "surfaceless" || index ? std::string() : "auto, surfaceless or a device index";
      });
  s.add_option(
      "--program-cache", c.program_cache,
      "where GL keeps linked shader programs between runs: auto (~/.cache/peakcast/programs) | off | a folder");
  s.add_option("--backend", c.backend,
               "auto (the CPU backend when EGL offers only a software rasteriser, else GL) | gl | cpu")
      ->check(CLI::IsMember({"auto", "gl", "cpu"}));
}

}  // namespace

std::string env_name(const std::string& key) {
  std::string e = "PEAKCAST_";
  for (char c : key) e += c == '-' ? '_' : char(std::toupper(static_cast<unsigned char>(c)));
  return e;
}

net::ServerConfig ServeOptions::resolved() const {
  net::ServerConfig c = server;
  for (auto& d : data) c.data_dirs.emplace_back(d);
  for (auto& v : volumes) c.volumes.emplace_back(v);
  c.idle_timeout = std::chrono::seconds(idle_seconds);
  c.gpu_budget_bytes = gpu_budget_mib << 20;
  c.memory_budget_bytes = memory_budget_mib << 20;
  c.web_dir = web_dir;
  c.shader_dir = shader_dir;
  c.upload_dir = upload_dir;
  c.upload_limits.max_bytes = max_upload_mib << 20;
  c.upload_limits.budget_bytes = upload_budget_mib << 20;
  c.upload_limits.max_concurrent = max_uploads;
  c.upload_limits.per_minute = uploads_per_minute;
  c.upload_limits.idle_timeout = std::chrono::seconds(upload_timeout);
  c.upload_limits.min_bytes_per_second = upload_min_rate_kib * 1024;
  c.upload_limits.deadline = std::chrono::seconds(upload_deadline);
  if (!token_file.empty()) {
    if (!c.token.empty()) throw std::invalid_argument("give --token or --token-file, not both");
    c.token = net::read_token_file(token_file);
  }
  if (!user_token_file.empty()) c.user_tokens = net::read_user_tokens(user_token_file);
  for (const std::string& h : c.allowed_hosts)
    if (h != "*" && net::host_name(h).empty())
      throw std::invalid_argument("--allowed-host '" + h +
                                  "' is not a host name (a name or an address; '*' for any; "
                                  "no wildcards in names)");
  return c;
}

void add_serve_options(CLI::App& s, ServeOptions& o) {
  net::ServerConfig& c = o.server;
  o.idle_seconds = int(c.idle_timeout.count());
  o.gpu_budget_mib = c.gpu_budget_bytes >> 20;
  o.web_dir = PEAKCAST_WEB_DIR_DEFAULT;
  o.shader_dir = render::default_shader_dir().string();
  c.egl_device = "auto";
  c.backend = "auto";
  c.program_cache = "auto";
  s.option_defaults()->always_capture_default();
  add_config_options(s, o);
  add_network_options(s, o);
  add_security_options(s, o);
  add_limit_options(s, o);
  add_logging_and_thread_options(s, o);
  add_upload_options(s, o);
  add_rendering_options(s, o);
  s.footer(
      "Every option is also a PEAKCAST_* environment variable (--max-fps: PEAKCAST_MAX_FPS; lists\n"
      "comma-separated) and a key of the --config TOML file (max-fps = 30; lists as arrays).\n"
      "Precedence: flag > environment > config file > default. --print-config shows the result.");
}

void apply_env_and_file(CLI::App& s, ServeOptions& o) {
  o.source.clear();
  const char* env_config = std::getenv("PEAKCAST_CONFIG");
  if (s.get_option("--config")->count() == 0 && env_config && *env_config) o.config_file = env_config;

  std::map<std::string, std::vector<std::string>> file;
  if (!o.config_file.empty()) {
    std::vector<CLI::ConfigItem> items;
    try {
      items = CLI::ConfigTOML().from_file(o.config_file);
    } catch (const CLI::Error& e) {
      throw std::invalid_argument("config file " + o.config_file + ": " + e.what());
    }
    for (const auto& item : items) {
      if (item.name == "++" || item.name == "--") continue;  // CLI11's section markers
      const bool top = item.parents.empty() || (item.parents.size() == 1 && item.parents[0] == "serve");
      const CLI::Option* opt = top ? s.get_option_no_throw("--" + item.name) : nullptr;
      if (!opt || kNotSettings.count(item.name))
        throw std::invalid_argument("config file " + o.config_file + ": '" + item.fullname() +
                                    "' is not a serve option (peakcast serve --help lists them)");
      file[item.name] = item.inputs;
    }
  }

  for (CLI::Option* opt : s.get_options()) {
    const std::string key = key_of(*opt);
    if (kNotSettings.count(key)) continue;
    const std::string env = env_name(key);
    const char* value = std::getenv(env.c_str());
    if (opt->count() > 0) {
      o.source[key] = "flag";
    } else if (value && *value) {  // an empty variable counts as unset
      const auto values = kLists.count(key) ? split_commas(value) : std::vector<std::string>{value};
      if (!values.empty()) set_from(*opt, values, env);  // "PEAKCAST_DATA=," is an empty list
      o.source[key] = "env " + env;
    } else if (auto it = file.find(key); it != file.end()) {
      std::vector<std::string> values = it->second;
      if (kLists.count(key))  // an empty TOML array leaves the list empty
        values.erase(std::remove(values.begin(), values.end(), std::string()), values.end());
      if (!values.empty()) set_from(*opt, values, "config file " + o.config_file + ", key " + key);
      o.source[key] = "file " + o.config_file;
    } else {
      o.source[key] = "default";
    }
  }
}

std::string print_config(const CLI::App& s, const ServeOptions& o) {
  std::ostringstream out;
  out << "# peakcast serve: the effective configuration (a --config file as it stands).\n"
      << "# Precedence: flag > PEAKCAST_* environment > config file > default.\n";
  for (const CLI::Option* opt : s.get_options()) {
    const std::string key = key_of(*opt);
    if (kNotSettings.count(key)) continue;
    auto src = o.source.find(key);
    const std::string from = src == o.source.end() ? "default" : src->second;
    std::string line;
    if (key == "token") {
      line = std::string("# token = ") + (o.server.token.empty() ? "(none: no authentication)" : "(set, not printed)");
    } else if (kLists.count(key)) {
      line = key + " = [";
      const auto& values = opt->count() > 0 ? opt->results() : std::vector<std::string>{};
      for (size_t i = 0; i < values.size(); ++i) line += (i ? ", " : "") + toml_value(values[i]);
      line += "]";
    } else {
      line = key + " = " + toml_value(opt->count() > 0 ? opt->results().back() : opt->get_default_str());
    }
    out << line << std::string(line.size() < 44 ? 44 - line.size() : 1, ' ') << "# " << from << "\n";
  }
  return out.str();
}

}  // namespace peakcast::app
