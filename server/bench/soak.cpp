// `bench soak`: a long run of busy, careless and hostile-but-legal traffic against an in-process
// server. Loopback WebSocket viewers send random camera, TF, render-settings,
// ping and stroke messages at 60 Hz and ack their frames; one client never acks; one connects
// and vanishes (no close frame) over and over; one fires bursts of REST stills past the queue
// bound. Checks, each printed with its figures, exit 1 when one fails:
//   every message that has an answer got it (ping -> pong, stroke -> stroke_ack)
//   no steady client lost its session; the vanished ones were all released
//   the non-acking client got exactly kMaxFramesInFlight frames
//   RSS after the first window (warm-up) grew by less than --max-rss-growth at the end
//   camera -> frame p95 of every window within --max-p95-ratio of the first window's
//   stills: each answered 200 or 503; a 503 at once (< 1 s); the queue never past its bound
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <thread>

#include "bench/bench_util.h"
#include "bench/commands.h"
#include "bench/soak_client.h"
#include "core/generators.h"
#include "render/backend.h"
#include "net/server.h"

namespace fs = std::filesystem;

namespace peakcast::bench {
namespace {

using namespace peakcast::net;
using nlohmann::json;

struct StillStats {
  std::mutex m;
  uint64_t ok = 0, refused = 0, slow_refusals = 0, failed = 0, checks = 0, over_bound = 0;
  size_t max_queued = 0;
  int min_sessions = 1 << 30;  // WebSocket sessions, sampled between warm-up and the end
  double max_ok_ms = 0, max_refusal_ms = 0;
  std::string first_failure;
};

struct SoakArgs {
  int clients = 20;
  double seconds = 300;
  double window = 60;
  int size = 160;
  double max_rss_growth = 0.05;
  double max_p95_ratio = 1.5;
  double burst_every = 10;
  std::string data_dir = "bench-data";
};

// Whether the client count and the lengths are usable; says why on stderr when they are not.
bool soak_args_valid(const SoakArgs& a) {
  if (a.clients < 4 || a.clients > 24) {
    std::fprintf(stderr,
                 "bench soak: --clients must be 4..24 (all connect from 127.0.0.1, which may hold %d connections)\n",
                 limits::kMaxConnectionsPerAddress);
    return false;
  }
  if (a.window <= 0 || a.seconds < 2 * a.window) {
    std::fprintf(stderr, "bench soak: --seconds must be at least two --window lengths\n");
    return false;
  }
  return true;
}

// The volume the server shows: blobs 96^3, generated into the data directory once.
fs::path soak_volume(const std::string& data_dir) {
  fs::create_directories(data_dir);
  const fs::path vol = fs::path(data_dir) / "blobs_96x96x96.raw";
  if (!fs::exists(vol)) {
    GeneratorSpec g;
    g.kind = GeneratorKind::Blobs;
    g.dims = {96, 96, 96};
    generate_to_file(g, vol);
  }
  return vol;
}

// Every 250 ms until `done`: the live WebSocket sessions (between warm-up and the end) and the
// still queue's depth against its bound from /api/health.
void monitor_soak(Server& server, uint16_t port, size_t max_queued_stills, const SoakStats& stats,
                  SoakClock::time_point end, const std::atomic<bool>& done, StillStats& still) {
  while (!done) {
    const auto now = Clock::now();
    if (now > stats.start + std::chrono::seconds(3) && now + std::chrono::milliseconds(500) < end) {
      std::lock_guard lock(still.m);
      still.min_sessions = std::min(still.min_sessions, server.app().ws_sessions.count());
    }
    const HttpAnswer h = http_request(port, http::verb::get, "/api/health", "");
    if (h.status == 200) {
      const json j = json::parse(h.body);
      std::lock_guard lock(still.m);
      still.checks++;
      const size_t q = j.value("stills_queued", size_t(0));
      still.max_queued = std::max(still.max_queued, q);
      if (q > j.value("max_queued_stills", max_queued_stills)) still.over_bound++;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
}

// One burst of `count` REST stills at once, each answer counted in `still`.
void fire_still_burst(uint16_t port, const std::string& scene, size_t count, StillStats& still) {
  std::vector<std::thread> burst;
  for (size_t k = 0; k < count; ++k)
    burst.emplace_back([&] {
      const HttpAnswer r = http_request(port, http::verb::post, "/api/render?format=jpeg", scene);
      std::lock_guard lock(still.m);
      if (r.status == 200) {
        still.ok++;
        still.max_ok_ms = std::max(still.max_ok_ms, r.ms);
      } else if (r.status == 503) {
        still.refused++;
        still.max_refusal_ms = std::max(still.max_refusal_ms, r.ms);
        if (r.ms > 1000) still.slow_refusals++;
      } else {
        still.failed++;
        if (still.first_failure.empty()) still.first_failure = std::to_string(r.status) + " " + r.body.substr(0, 200);
      }
    });
  for (auto& t : burst) t.join();
}

// Until `end`: a burst of stills past the queue bound every --burst-every seconds, and the RSS at
// the end of each window.
void run_stills(const SoakArgs& a, uint16_t port, const std::string& scene, size_t max_queued_stills,
                const SoakStats& stats, SoakClock::time_point end, StillStats& still,
                std::vector<double>& rss_at_window) {
  auto next_burst = Clock::now() + std::chrono::seconds(2);
  auto next_window = stats.start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.window));
  while (Clock::now() < end) {
    if (Clock::now() >= next_window) {
      rss_at_window.push_back(rss_mib());
      next_window += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.window));
    }
    if (Clock::now() >= next_burst && Clock::now() + std::chrono::seconds(3) < end) {
      fire_still_burst(port, scene, max_queued_stills + 2, still);
      next_burst =
          Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.burst_every));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

// What the run left for the report beside the clients' and the stills' counts.
struct SoakEnd {
  int steady = 0;          // viewers + the non-acking client
  int sessions_after = 0;  // sessions still open once every client is done
  double rss_end = 0;
  size_t max_queued_stills = 0;
  std::vector<double> rss_at_window;
};

// Prints the table of windows and every check with its figures; true when all passed.
bool report_soak(const SoakArgs& a, SoakStats& stats, const StillStats& still, const SoakEnd& e) {
  std::lock_guard lock(stats.m);
  bool ok = true;
  auto check = [&](bool pass, const std::string& what) {
    std::printf("  %-4s %s\n", pass ? "ok" : "FAIL", what.c_str());
    ok = ok && pass;
  };
  const std::vector<double>& rss_at_window = e.rss_at_window;
  const double rss_end = e.rss_end;
  std::printf("%6s %9s %9s %8s\n", "window", "frames", "p95_ms", "rss_MiB");
  std::vector<double> p95;
  for (size_t w = 0; w < stats.latency_ms.size(); ++w) {
    p95.push_back(percentile(stats.latency_ms[w], 0.95));
    std::printf("%6zu %9zu %9.1f %8.0f\n", w, stats.latency_ms[w].size(), p95.back(),
                w < rss_at_window.size() ? rss_at_window[w] : rss_end);
  }
  std::printf("messages sent %llu, frames %llu, answers %llu of %llu expected\n", (unsigned long long)stats.sent,
              (unsigned long long)stats.frames, (unsigned long long)stats.answers,
              (unsigned long long)stats.expected_answers);
  check(stats.answers == stats.expected_answers && stats.unexpected_errors == 0,
        "every ping and stroke answered; unexpected errors: " + std::to_string(stats.unexpected_errors) +
            (stats.first_unexpected.empty() ? "" : " (" + stats.first_unexpected + ")"));
  check(stats.lost_sessions == 0 && still.min_sessions >= e.steady && still.min_sessions <= e.steady + 1,
        "steady sessions kept: at least " + std::to_string(still.min_sessions) + " live throughout, of " +
            std::to_string(e.steady) + " (+ the vanisher), lost " + std::to_string(stats.lost_sessions));
  check(e.sessions_after == 0, "every session released after " + std::to_string(stats.vanished) +
                                   " vanished connections and the clients' close: " + std::to_string(e.sessions_after) +
                                   " left");
  check(stats.noack_frames == uint64_t(limits::kMaxFramesInFlight),
        "the non-acking client got " + std::to_string(stats.noack_frames) + " frames (at most " +
            std::to_string(limits::kMaxFramesInFlight) + " in flight)");
  const double rss0 = rss_at_window.empty() ? rss_end : rss_at_window.front();
  char line[256];
  std::snprintf(line, sizeof line, "RSS after warm-up %.0f MiB -> end %.0f MiB (%+.1f%%, bound %.0f%%)", rss0, rss_end,
                100.0 * (rss_end / rss0 - 1.0), 100.0 * a.max_rss_growth);
  check(rss_end <= rss0 * (1.0 + a.max_rss_growth), line);
  double worst = 0;
  for (size_t w = 1; w < p95.size(); ++w)
    if (stats.latency_ms[w].size() >= 20) worst = std::max(worst, p95[w] / p95[0]);
  std::snprintf(line, sizeof line, "camera -> frame p95: first window %.1f ms, worst later window %.2fx (bound %.2fx)",
                p95.empty() ? NAN : p95[0], worst, a.max_p95_ratio);
  check(!p95.empty() && stats.latency_ms[0].size() >= 20 && worst <= a.max_p95_ratio, line);
  std::snprintf(
      line, sizeof line,
      "stills: %llu rendered (slowest %.0f ms), %llu refused with 503 (slowest answer %.0f ms), %llu failed%s",
      (unsigned long long)still.ok, still.max_ok_ms, (unsigned long long)still.refused, still.max_refusal_ms,
      (unsigned long long)still.failed, still.first_failure.empty() ? "" : (": " + still.first_failure).c_str());
  check(still.failed == 0 && still.slow_refusals == 0 && still.ok > 0 && still.refused > 0, line);
  std::snprintf(line, sizeof line, "still queue: at most %zu waiting or rendering over %llu health checks (bound %zu)",
                still.max_queued, (unsigned long long)still.checks, e.max_queued_stills);
  check(still.over_bound == 0 && still.checks > 0, line);
  std::printf("bench soak: %s\n", ok ? "all checks passed" : "FAILED");
  return ok;
}

int run_soak(const SoakArgs& a) {
  if (!soak_args_valid(a)) return kExitBadInput;
  const fs::path vol = soak_volume(a.data_dir);
  ServerConfig cfg;
  cfg.port = 0;
  cfg.volumes = {vol};
  cfg.data_dirs = {a.data_dir};
  cfg.max_sessions = a.clients + 2;
  cfg.shader_dir = render::default_shader_dir();
  Server server(cfg);
  server.start();
  const uint16_t port = server.port();
  SoakEnd e;
  e.steady = a.clients - 1;  // viewers + the non-acking client; the vanisher comes and goes
  e.max_queued_stills = cfg.max_queued_stills;
  std::printf(
      "bench soak: %d clients (%d viewers at 60 Hz, 1 never acks, 1 vanishes and returns, stills in bursts of %zu "
      "every %.0f s) for %.0f s, windows of %.0f s\n",
      a.clients + 1, a.clients - 2, cfg.max_queued_stills + 2, a.burst_every, a.seconds, a.window);
  std::fflush(stdout);

  SoakStats stats;
  stats.start = Clock::now();
  stats.window_s = a.window;
  const auto end = stats.start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.seconds));
  asio::io_context ioc;
  for (int i = 0; i < a.clients; ++i) {
    const SoakClientKind k = i == 0   ? SoakClientKind::NoAck
                             : i == 1 ? SoakClientKind::Vanisher
                                      : SoakClientKind::Viewer;
    start_soak_client(ioc, port, k, a.size, 1234u + unsigned(i), stats, end);
  }
  std::thread clients([&] { ioc.run(); });

  // Stills: bursts past the queue bound; health sampled for the queue depth; RSS per window.
  StillStats still;
  std::atomic<bool> done{false};
  std::thread monitor([&] { monitor_soak(server, port, cfg.max_queued_stills, stats, end, done, still); });
  const std::string scene = json{{"volume", vol.stem().string()},
                                 {"image", {{"width", 384}, {"height", 384}}},
                                 {"render", {{"step", 0.25}, {"shading", true}}}}
                                .dump();
  std::thread stills([&] { run_stills(a, port, scene, cfg.max_queued_stills, stats, end, still, e.rss_at_window); });
  stills.join();
  clients.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  e.sessions_after = server.app().ws_sessions.count();
  done = true;
  monitor.join();
  e.rss_end = rss_mib();
  server.stop();

  // The report.
  return report_soak(a, stats, still, e) ? 0 : kExitFailure;
}

}  // namespace

void add_soak_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<SoakArgs>();
  auto* s = bench.add_subcommand("soak",
                                 "Long run of random, careless and hostile clients against an in-process server; "
                                 "checks answers, sessions, memory, latency and the still queue");
  s->add_option("--clients", a->clients,
                "WebSocket clients (4..24): 1 never acks, 1 vanishes and returns, the rest view");
  s->add_option("--seconds", a->seconds, "duration");
  s->add_option("--window", a->window, "length of a latency/RSS window in seconds; the first is the warm-up");
  s->add_option("--size", a->size, "square viewport of each client in pixels");
  s->add_option("--max-rss-growth", a->max_rss_growth, "allowed RSS growth after the first window (fraction)");
  s->add_option("--max-p95-ratio", a->max_p95_ratio, "allowed p95 latency of a window over the first window's");
  s->add_option("--burst-every", a->burst_every, "seconds between bursts of REST stills");
  s->add_option("--data-dir", a->data_dir, "where the generated volume is cached");
  s->callback([a, &run] { run = [a] { return run_soak(*a); }; });
}

}  // namespace peakcast::bench
