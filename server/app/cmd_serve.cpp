// `serve`: the render server. Options come from flags, then PEAKCAST_* environment variables,
// then an optional config file (CLI11's TOML/INI: `--config FILE`).
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "app/commands.h"
#include "core/log.h"
#include "gpu/shader_cache.h"
#include "net/server.h"

namespace peakcast::app {

void add_serve_command(CLI::App& app, Runner& run) {
  auto cfg = std::make_shared<net::ServerConfig>();
  auto web = std::make_shared<std::string>(PEAKCAST_WEB_DIR_DEFAULT);
  auto data = std::make_shared<std::vector<std::string>>();
  auto vols = std::make_shared<std::vector<std::string>>();
  auto idle = std::make_shared<int>(int(cfg->idle_timeout.count()));
  auto budget_mib = std::make_shared<int64_t>(cfg->gpu_budget_bytes >> 20);
  auto* s = app.add_subcommand("serve", "Run the render server (HTTP + WebSocket on one port)");
  s->set_config("--config", "", "read options from a TOML/INI file");
  s->add_option("--bind", cfg->bind, "address to listen on (default loopback only)")->envname("PEAKCAST_BIND");
  s->add_option("--port", cfg->port, "TCP port (0: any free port)")->envname("PEAKCAST_PORT");
  s->add_option("--data", *data, "directory volumes may be opened from (repeatable)")->envname("PEAKCAST_DATA");
  s->add_option("--volume", *vols, "volume to preload (repeatable; the first is the default view)")
      ->envname("PEAKCAST_VOLUME");
  s->add_option("--token", cfg->token, "require this bearer token (HTTP header, ?token= or hello.token)")
      ->envname("PEAKCAST_TOKEN");
  s->add_option("--allow-origin", cfg->allow_origins, "WebSocket Origin to accept besides the server's own (repeatable)")
      ->envname("PEAKCAST_ALLOW_ORIGIN");
  s->add_option("--max-sessions", cfg->max_sessions, "concurrent WebSocket sessions")->check(CLI::Range(1, 4096));
  s->add_option("--idle-timeout", *idle, "seconds without a client message before closing")->check(CLI::Range(1, 86400));
  s->add_option("--max-fps", cfg->max_fps, "frames per second per session")->check(CLI::Range(1.0, 240.0));
  s->add_option("--gpu-budget-mib", *budget_mib, "MiB of volume textures on the GPU")->check(CLI::Range(int64_t(1), int64_t(1) << 24));
  s->add_option("--max-queued-stills", cfg->max_queued_stills,
                "REST stills waiting or rendering at once; beyond, 503 with Retry-After")
      ->check(CLI::Range(size_t(1), size_t(1024)))
      ->envname("PEAKCAST_MAX_QUEUED_STILLS");
  s->add_option("--max-still-samples", cfg->max_still_samples,
                "cost cap of one REST still: pixels x estimated samples per ray; beyond, 422")
      ->check(CLI::Range(1e3, 1e15))
      ->envname("PEAKCAST_MAX_STILL_SAMPLES");
  s->add_option("--still-band-samples", cfg->still_band_samples,
                "estimated samples per band of a still (bands alternate with viewers' frames)")
      ->check(CLI::Range(1e3, 1e12));
  auto log_level = std::make_shared<std::string>("info");
  auto log_format = std::make_shared<std::string>("text");
  s->add_option("--log-level", *log_level, "debug | info | warn | error | off (stderr)")
      ->check(CLI::IsMember({"debug", "info", "warn", "error", "off"}))
      ->envname("PEAKCAST_LOG_LEVEL");
  s->add_option("--log-format", *log_format, "text | json (one JSON object per line)")
      ->check(CLI::IsMember({"text", "json"}))
      ->envname("PEAKCAST_LOG_FORMAT");
  s->add_option("--io-threads", cfg->io_threads, "network threads")->check(CLI::Range(1, 64));
  s->add_option("--encode-threads", cfg->encode_threads, "JPEG encode threads")->check(CLI::Range(1, 64));
  s->add_option("--web-dir", *web, "the browser client's files");
  s->callback([=, &run] {
    run = [=] {
      log::configure(log::parse_level(*log_level), log::parse_format(*log_format));
      net::ServerConfig c = *cfg;
      for (auto& d : *data) c.data_dirs.emplace_back(d);
      for (auto& v : *vols) c.volumes.emplace_back(v);
      c.idle_timeout = std::chrono::seconds(*idle);
      c.gpu_budget_bytes = *budget_mib << 20;
      c.web_dir = *web;
      c.shader_dir = gpu::default_shader_dir();
      net::Server server(c);
      server.start();
      // This line on stdout is the contract scripts and tests wait for; the log goes to stderr.
      std::printf("peakcast: serving on http://%s:%u (GL: %s)\n", c.bind.c_str(), unsigned(server.port()),
                  server.app().render.gl_renderer().c_str());
      log::info("serving", {{"bind", c.bind}, {"port", server.port()}, {"gl", server.app().render.gl_renderer()}});
      std::fflush(stdout);
      server.run_until_signal();
      std::printf("peakcast: stopped\n");
      return 0;
    };
  });
}

}  // namespace peakcast::app
