// `bench soak`: a long run of busy, careless and hostile-but-legal traffic against an in-process
// server (issue 14 §3). Loopback WebSocket viewers send random camera, TF, render-settings,
// ping and stroke messages at 60 Hz and ack their frames; one client never acks; one connects
// and vanishes (no close frame) over and over; one fires bursts of REST stills past the queue
// bound. Checks, each printed with its figures, exit 1 when one fails:
//   every message that has an answer got it (ping -> pong, stroke -> error until ray textures land)
//   no steady client lost its session; the vanished ones were all released
//   the non-acking client got exactly kMaxFramesInFlight frames
//   RSS after the first window (warm-up) grew by less than --max-rss-growth at the end
//   camera -> frame p95 of every window within --max-p95-ratio of the first window's
//   stills: each answered 200 or 503; a 503 at once (< 1 s); the queue never past its bound
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <thread>

#include "app/commands.h"
#include "core/generators.h"
#include "gpu/shader_cache.h"
#include "net/beast.h"
#include "net/server.h"
#include "session/protocol.h"

namespace fs = std::filesystem;

namespace peakcast::app {
namespace {

using namespace peakcast::net;
using nlohmann::json;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

double rss_mib() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

struct SoakStats {
  std::mutex m;
  Clock::time_point start;
  double window_s = 60;
  std::vector<std::vector<double>> latency_ms;  // per window: camera sent -> first frame showing it
  uint64_t sent = 0, frames = 0, expected_answers = 0, answers = 0, unexpected_errors = 0;
  uint64_t lost_sessions = 0, vanished = 0, noack_frames = 0;
  std::string first_unexpected;

  void latency(Clock::time_point sent_at, Clock::time_point now) {
    const size_t w = size_t(std::chrono::duration<double>(sent_at - start).count() / window_s);
    std::lock_guard lock(m);
    if (latency_ms.size() <= w) latency_ms.resize(w + 1);
    latency_ms[w].push_back(ms_between(sent_at, now));
  }
};

enum class Kind { Viewer, NoAck, Vanisher };

// One WebSocket client. Viewers and the non-acking client run until `end`; the vanisher
// reconnects after each abrupt close until `end`.
class SoakClient : public std::enable_shared_from_this<SoakClient> {
 public:
  SoakClient(asio::io_context& ioc, uint16_t port, Kind kind, int size, unsigned seed, SoakStats& out,
             Clock::time_point end)
      : ioc_(ioc), ws_(std::make_unique<Ws>(asio::make_strand(ioc))), timer_(ioc), port_(port), kind_(kind),
        size_(size), rng_(seed), out_(out), end_(end) {}

  void start() {
    auto self = shared_from_this();
    beast::get_lowest_layer(*ws_).async_connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port_),
                                                [self](beast::error_code ec) {
                                                  if (ec) return self->lost("connect: " + ec.message());
                                                  self->ws_->async_handshake("127.0.0.1", "/ws", [self](beast::error_code e) {
                                                    if (e) return self->lost("handshake: " + e.message());
                                                    self->send(json{{"type", "hello"}, {"viewport", {{"width", self->size_}, {"height", self->size_}}}}.dump());
                                                    self->read();
                                                    self->tick();
                                                  });
                                                });
  }

 private:
  using Ws = websocket::stream<beast::tcp_stream>;

  void lost(const std::string& why) {
    if (closing_) return;
    std::lock_guard lock(out_.m);
    out_.lost_sessions++;
    if (out_.first_unexpected.empty()) out_.first_unexpected = "session lost: " + why;
  }
  void send(std::string text) {
    queue_.push_back(std::move(text));
    {
      std::lock_guard lock(out_.m);
      out_.sent++;
    }
    if (queue_.size() == 1) write();
  }
  void write() {
    ws_->text(true);
    ws_->async_write(asio::buffer(queue_.front()), [self = shared_from_this(), gen = gen_](beast::error_code ec, std::size_t) {
      if (ec || gen != self->gen_) return;
      self->queue_.pop_front();
      if (!self->queue_.empty()) self->write();
    });
  }
  void tick() {
    const auto now = Clock::now();
    if (now >= end_) {
      closing_ = true;
      ws_->async_close(websocket::close_code::normal, [self = shared_from_this()](beast::error_code) {});
      return;
    }
    if (kind_ == Kind::Vanisher && now >= vanish_at_) return vanish();
    // The last second is quiet: every answer to what was sent arrives before the close.
    if (welcomed_ && now + std::chrono::seconds(1) < end_) random_message(now);
    timer_.expires_after(std::chrono::microseconds(16667));  // 60 Hz
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->tick();
    });
  }
  // The TCP connection closes with no WebSocket close frame, as a crashed browser tab's does;
  // a new connection follows.
  void vanish() {
    closing_ = true;
    beast::error_code ec;
    beast::get_lowest_layer(*ws_).socket().close(ec);
    {
      std::lock_guard lock(out_.m);
      out_.vanished++;
    }
    timer_.expires_after(std::chrono::milliseconds(50));
    timer_.async_wait([self = shared_from_this()](beast::error_code) {
      self->ws_ = std::make_unique<Ws>(asio::make_strand(self->ioc_));
      self->gen_++;
      self->queue_.clear();
      self->buffer_.clear();
      self->closing_ = self->welcomed_ = false;
      self->vanish_at_ = Clock::now() + std::chrono::milliseconds(std::uniform_int_distribution<int>(100, 800)(self->rng_));
      self->start();
    });
  }
  void random_message(Clock::time_point now) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double r = kind_ == Kind::Viewer ? u(rng_) : 0.0;  // the others only move the camera
    if (r < 0.6) {
      angle_ += u(rng_) * 0.2 - 0.05;
      const double e[3] = {center_[0] + radius_ * std::sin(angle_), center_[1] + 0.2 * radius_ * std::sin(3 * angle_),
                           center_[2] + radius_ * std::cos(angle_)};
      send(json{{"type", "camera"},
                {"camera", {{"eye", {e[0], e[1], e[2]}}, {"center", center_}, {"up", {0, 1, 0}}}}}.dump());
      sent_[++camera_version_] = now;
    } else if (r < 0.75) {
      const double a = u(rng_);
      send(json{{"type", "tf"}, {"version", ++tf_version_},
                {"tf", {{"points", {{lo_, 0, 0, 0, 0}, {lo_ + (hi_ - lo_) * (0.2 + 0.6 * u(rng_)), 1, 0.5, 0.2, a}, {hi_, 1, 1, 1, a}}}}}}
               .dump());
    } else if (r < 0.85) {
      static const json patches[] = {{{"shading", true}}, {{"shading", false}}, {{"filter", "tricubic"}},
                                     {{"filter", "trilinear"}}, {{"classification", "peaks"}}, {{"classification", "post"}}};
      send(json{{"type", "render"}, {"render", patches[std::uniform_int_distribution<size_t>(0, 5)(rng_)]}}.dump());
    } else if (r < 0.95) {
      send(json{{"type", "ping"}, {"id", "p" + std::to_string(++pings_)}}.dump());
      expect();
    } else {
      // A ray-texture stroke (proto/messages.md): refused with an error until ray textures land.
      send(json{{"type", "stroke"}, {"channel", "step"}, {"center", {u(rng_), u(rng_)}}, {"radius", 0.05},
                {"falloff", 0.5}, {"value", 2.0}, {"mode", "set"}, {"level", 0}}.dump());
      expect();
    }
  }
  void expect() {
    std::lock_guard lock(out_.m);
    out_.expected_answers++;
  }
  void read() {
    ws_->async_read(buffer_, [self = shared_from_this(), gen = gen_](beast::error_code ec, std::size_t) {
      if (gen != self->gen_) return;  // a vanished connection's last read
      if (ec) {
        if (ec != websocket::error::closed) self->lost("read: " + ec.message());
        return;
      }
      self->on_message();
      self->read();
    });
  }
  void on_message() {
    const auto now = Clock::now();
    if (ws_->got_binary()) {
      std::vector<uint8_t> bytes(buffer_.size());
      asio::buffer_copy(asio::buffer(bytes), buffer_.data());
      buffer_.consume(buffer_.size());
      const auto h = protocol::decode_frame_header(bytes.data(), bytes.size());
      {
        std::lock_guard lock(out_.m);
        out_.frames++;
        if (kind_ == Kind::NoAck) out_.noack_frames++;
      }
      if (kind_ == Kind::NoAck) return;
      send(json{{"type", "ack"}, {"frame", h.frame_id}}.dump());
      for (auto it = sent_.begin(); it != sent_.end() && it->first <= h.camera_version;) {  // first frame showing each
        out_.latency(it->second, now);
        it = sent_.erase(it);
      }
      return;
    }
    const json j = json::parse(beast::buffers_to_string(buffer_.data()));
    buffer_.consume(buffer_.size());
    const std::string type = j.value("type", "");
    if (type == "welcome") {
      const auto& c = j["state"]["camera"];
      double d = 0;
      for (size_t k = 0; k < 3; ++k) {
        center_[k] = c["center"][k];
        d += std::pow(double(c["eye"][k]) - center_[k], 2);
      }
      radius_ = std::sqrt(d);
      lo_ = j["volume"]["range"][0];
      hi_ = j["volume"]["range"][1];
      camera_version_ = j["state"]["versions"].value("camera", 1u);
      tf_version_ = j["state"]["versions"].value("tf", 1u);
      welcomed_ = true;
    } else if (type == "pong" || (type == "error" && j.value("code", "") == "unknown_type")) {
      std::lock_guard lock(out_.m);
      out_.answers++;
    } else if (type == "error") {
      std::lock_guard lock(out_.m);
      out_.unexpected_errors++;
      if (out_.first_unexpected.empty()) out_.first_unexpected = j.dump();
    }
  }

  asio::io_context& ioc_;
  std::unique_ptr<Ws> ws_;
  asio::steady_timer timer_;
  beast::flat_buffer buffer_;
  std::deque<std::string> queue_;
  uint16_t port_;
  Kind kind_;
  int size_;
  std::mt19937 rng_;
  SoakStats& out_;
  Clock::time_point end_, vanish_at_ = Clock::now() + std::chrono::milliseconds(300);
  bool welcomed_ = false, closing_ = false;
  std::array<double, 3> center_{0, 0, 0};
  double radius_ = 1, angle_ = 0, lo_ = 0, hi_ = 1;
  uint32_t camera_version_ = 1, tf_version_ = 1;
  uint64_t pings_ = 0;
  unsigned gen_ = 0;  // connection number: handlers of a vanished connection do nothing
  std::map<uint32_t, Clock::time_point> sent_;
};

struct HttpAnswer {
  int status = 0;
  std::string body;
  double ms = 0;
};

// One blocking HTTP request on its own connection.
HttpAnswer http_request(uint16_t port, http::verb verb, const std::string& target, const std::string& body) {
  HttpAnswer a;
  const auto t0 = Clock::now();
  try {
    asio::io_context ioc;
    beast::tcp_stream s(ioc);
    s.expires_after(std::chrono::seconds(300));
    s.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), port));
    http::request<http::string_body> req{verb, target, 11};
    req.set(http::field::host, "127.0.0.1");
    req.set(http::field::content_type, "application/json");
    req.body() = body;
    req.prepare_payload();
    http::write(s, req);
    beast::flat_buffer buf;
    http::response<http::string_body> res;
    http::read(s, buf, res);
    a.status = int(res.result_int());
    a.body = std::move(res.body());
  } catch (const std::exception& e) {
    a.body = e.what();
  }
  a.ms = ms_between(t0, Clock::now());
  return a;
}

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

int run_soak(const SoakArgs& a) {
  if (a.clients < 4 || a.clients > 24) {
    std::fprintf(stderr, "bench soak: --clients must be 4..24 (all connect from 127.0.0.1, which may hold %d connections)\n",
                 limits::kMaxConnectionsPerAddress);
    return kExitBadInput;
  }
  if (a.window <= 0 || a.seconds < 2 * a.window) {
    std::fprintf(stderr, "bench soak: --seconds must be at least two --window lengths\n");
    return kExitBadInput;
  }
  fs::create_directories(a.data_dir);
  const fs::path vol = fs::path(a.data_dir) / "blobs_96x96x96.raw";
  if (!fs::exists(vol)) {
    GeneratorSpec g;
    g.kind = GeneratorKind::Blobs;
    g.dims = {96, 96, 96};
    generate_to_file(g, vol);
  }
  ServerConfig cfg;
  cfg.port = 0;
  cfg.volumes = {vol};
  cfg.data_dirs = {a.data_dir};
  cfg.max_sessions = a.clients + 2;
  cfg.shader_dir = gpu::default_shader_dir();
  Server server(cfg);
  server.start();
  const uint16_t port = server.port();
  const int steady = a.clients - 1;  // viewers + the non-acking client; the vanisher comes and goes
  std::printf("bench soak: %d clients (%d viewers at 60 Hz, 1 never acks, 1 vanishes and returns, stills in bursts of %zu "
              "every %.0f s) for %.0f s, windows of %.0f s\n",
              a.clients + 1, a.clients - 2, cfg.max_queued_stills + 2, a.burst_every, a.seconds, a.window);
  std::fflush(stdout);

  SoakStats stats;
  stats.start = Clock::now();
  stats.window_s = a.window;
  const auto end = stats.start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.seconds));
  asio::io_context ioc;
  for (int i = 0; i < a.clients; ++i) {
    const Kind k = i == 0 ? Kind::NoAck : i == 1 ? Kind::Vanisher : Kind::Viewer;
    std::make_shared<SoakClient>(ioc, port, k, a.size, 1234u + unsigned(i), stats, end)->start();
  }
  std::thread clients([&] { ioc.run(); });

  // Stills: bursts past the queue bound; health sampled for the queue depth; RSS per window.
  StillStats still;
  std::atomic<bool> done{false};
  std::thread monitor([&] {
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
        if (q > j.value("max_queued_stills", cfg.max_queued_stills)) still.over_bound++;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  });
  const std::string scene = json{{"volume", vol.stem().string()}, {"image", {{"width", 384}, {"height", 384}}},
                                 {"render", {{"step", 0.25}, {"shading", true}}}}.dump();
  std::vector<double> rss_at_window;
  std::thread stills([&] {
    auto next_burst = Clock::now() + std::chrono::seconds(2);
    auto next_window = stats.start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.window));
    while (Clock::now() < end) {
      if (Clock::now() >= next_window) {
        rss_at_window.push_back(rss_mib());
        next_window += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.window));
      }
      if (Clock::now() >= next_burst && Clock::now() + std::chrono::seconds(3) < end) {
        std::vector<std::thread> burst;
        for (size_t k = 0; k < cfg.max_queued_stills + 2; ++k)
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
        next_burst = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.burst_every));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  stills.join();
  clients.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const int sessions_after = server.app().ws_sessions.count();
  done = true;
  monitor.join();
  const double rss_end = rss_mib();
  server.stop();

  // The report.
  std::lock_guard lock(stats.m);
  bool ok = true;
  auto check = [&](bool pass, const std::string& what) {
    std::printf("  %-4s %s\n", pass ? "ok" : "FAIL", what.c_str());
    ok = ok && pass;
  };
  std::printf("%6s %9s %9s %8s\n", "window", "frames", "p95_ms", "rss_MiB");
  std::vector<double> p95;
  for (size_t w = 0; w < stats.latency_ms.size(); ++w) {
    p95.push_back(percentile(stats.latency_ms[w], 0.95));
    std::printf("%6zu %9zu %9.1f %8.0f\n", w, stats.latency_ms[w].size(), p95.back(),
                w < rss_at_window.size() ? rss_at_window[w] : rss_end);
  }
  std::printf("messages sent %llu, frames %llu, answers %llu of %llu expected\n", (unsigned long long)stats.sent,
              (unsigned long long)stats.frames, (unsigned long long)stats.answers, (unsigned long long)stats.expected_answers);
  check(stats.answers == stats.expected_answers && stats.unexpected_errors == 0,
        "every ping answered and every stroke refused; unexpected errors: " + std::to_string(stats.unexpected_errors) +
            (stats.first_unexpected.empty() ? "" : " (" + stats.first_unexpected + ")"));
  check(stats.lost_sessions == 0 && still.min_sessions >= steady && still.min_sessions <= steady + 1,
        "steady sessions kept: at least " + std::to_string(still.min_sessions) + " live throughout, of " +
            std::to_string(steady) + " (+ the vanisher), lost " + std::to_string(stats.lost_sessions));
  check(sessions_after == 0, "every session released after " + std::to_string(stats.vanished) +
                                 " vanished connections and the clients' close: " + std::to_string(sessions_after) + " left");
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
  std::snprintf(line, sizeof line,
                "stills: %llu rendered (slowest %.0f ms), %llu refused with 503 (slowest answer %.0f ms), %llu failed%s",
                (unsigned long long)still.ok, still.max_ok_ms, (unsigned long long)still.refused, still.max_refusal_ms,
                (unsigned long long)still.failed, still.first_failure.empty() ? "" : (": " + still.first_failure).c_str());
  check(still.failed == 0 && still.slow_refusals == 0 && still.ok > 0 && still.refused > 0, line);
  std::snprintf(line, sizeof line, "still queue: at most %zu waiting or rendering over %llu health checks (bound %zu)",
                still.max_queued, (unsigned long long)still.checks, cfg.max_queued_stills);
  check(still.over_bound == 0 && still.checks > 0, line);
  std::printf("bench soak: %s\n", ok ? "all checks passed" : "FAILED");
  return ok ? 0 : kExitFailure;
}

}  // namespace

void add_bench_soak_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<SoakArgs>();
  auto* s = bench.add_subcommand("soak", "Long run of random, careless and hostile clients against an in-process server; "
                                         "checks answers, sessions, memory, latency and the still queue");
  s->add_option("--clients", a->clients, "WebSocket clients (4..24): 1 never acks, 1 vanishes and returns, the rest view");
  s->add_option("--seconds", a->seconds, "duration");
  s->add_option("--window", a->window, "length of a latency/RSS window in seconds; the first is the warm-up");
  s->add_option("--size", a->size, "square viewport of each client in pixels");
  s->add_option("--max-rss-growth", a->max_rss_growth, "allowed RSS growth after the first window (fraction)");
  s->add_option("--max-p95-ratio", a->max_p95_ratio, "allowed p95 latency of a window over the first window's");
  s->add_option("--burst-every", a->burst_every, "seconds between bursts of REST stills");
  s->add_option("--data-dir", a->data_dir, "where the generated volume is cached");
  s->callback([a, &run] { run = [a] { return run_soak(*a); }; });
}

}  // namespace peakcast::app
