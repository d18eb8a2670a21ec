// `bench serve`: N loopback WebSocket clients orbit the camera at 30 Hz against an in-process
// server (1 s of motion, 0.5 s pause, repeated, so both interactive and still frames happen).
// Prints camera-event -> frame-received latency p50/p95 per kind, frames/s per client,
// bytes/frame, encode ms per megapixel, and the process's CPU time and peak RSS.
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>

#include <glm/geometric.hpp>

#include "bench/bench_util.h"
#include "bench/commands.h"
#include "core/generators.h"
#include "render/backend.h"
#include "net/beast.h"
#include "net/server.h"
#include "session/protocol.h"

namespace fs = std::filesystem;

namespace peakcast::bench {
namespace {

using namespace peakcast::net;

struct Samples {
  std::mutex m;
  std::vector<double> interactive_ms, final_ms, encode_ms_per_mp;
  uint64_t frames = 0, bytes = 0;
};

class BenchClient : public std::enable_shared_from_this<BenchClient> {
 public:
  BenchClient(asio::io_context& ioc, uint16_t port, int size, int index, Samples& out, Clock::time_point end)
      : ws_(asio::make_strand(ioc)),
        timer_(ws_.get_executor()),
        port_(port),
        size_(size),
        index_(index),
        out_(out),
        end_(end) {}

  void start() {
    auto self = shared_from_this();
    beast::get_lowest_layer(ws_).async_connect(
        tcp::endpoint(asio::ip::make_address("127.0.0.1"), port_), [self](beast::error_code ec) {
          if (ec) return fail(ec, "bench connect");
          self->ws_.async_handshake("127.0.0.1", "/ws", [self](beast::error_code ec2) {
            if (ec2) return fail(ec2, "bench handshake");
            self->hello();
          });
        });
  }

 private:
  void send(std::string text) {
    queue_.push_back(std::move(text));
    if (queue_.size() == 1) write();
  }
  void write() {
    ws_.text(true);
    ws_.async_write(asio::buffer(queue_.front()), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return;
      self->queue_.pop_front();
      if (!self->queue_.empty()) self->write();
    });
  }
  void hello() {
    send(nlohmann::json{{"type", "hello"}, {"viewport", {{"width", size_}, {"height", size_}}}}.dump());
    read();
    tick();
  }
  void tick() {
    const auto now = Clock::now();
    if (now >= end_) {
      ws_.async_close(websocket::close_code::normal, [self = shared_from_this()](beast::error_code) {});
      return;
    }
    // 1 s of orbit, 0.5 s still, phase-shifted per client.
    const double t = std::chrono::duration<double>(now.time_since_epoch()).count() + 0.37 * index_;
    if (std::fmod(t, 1.5) < 1.0 && center_ready_) {
      angle_ += 2 * M_PI / 90.0;  // a full turn every 3 s of motion
      const glm::dvec3 eye = center_ + radius_ * glm::dvec3(std::sin(angle_), 0.0, std::cos(angle_));
      send(nlohmann::json{
          {"type", "camera"},
          {"camera",
           {{"eye", {eye.x, eye.y, eye.z}}, {"center", {center_.x, center_.y, center_.z}}, {"up", {0, 1, 0}}}}}
               .dump());
      sent_[++version_] = Clock::now();
    }
    timer_.expires_after(std::chrono::milliseconds(33));
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->tick();
    });
  }
  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return;
      self->on_message();
      self->read();
    });
  }
  void on_message() {
    const auto now = Clock::now();
    if (ws_.got_binary()) {
      std::vector<uint8_t> bytes(buffer_.size());
      asio::buffer_copy(asio::buffer(bytes), buffer_.data());
      const auto h = protocol::decode_frame_header(bytes.data(), bytes.size());
      send(nlohmann::json{{"type", "ack"}, {"frame", h.frame_id}}.dump());
      auto it = sent_.find(h.camera_version);
      std::lock_guard lock(out_.m);
      out_.frames++;
      out_.bytes += bytes.size();
      if (it != sent_.end()) {
        const double ms = std::chrono::duration<double, std::milli>(now - it->second).count();
        (h.flags & protocol::FrameHeader::kFinal ? out_.final_ms : out_.interactive_ms).push_back(ms);
      }
    } else {
      auto j = nlohmann::json::parse(beast::buffers_to_string(buffer_.data()));
      if (j["type"] == "welcome") {
        const auto& c = j["state"]["camera"];
        center_ = {c["center"][0], c["center"][1], c["center"][2]};
        const glm::dvec3 eye = {c["eye"][0], c["eye"][1], c["eye"][2]};
        radius_ = glm::length(eye - center_);
        version_ = 1;
        center_ready_ = true;
      } else if (j["type"] == "stats") {
        const double mp = double(j["width"]) * double(j["height"]) / 1e6;
        std::lock_guard lock(out_.m);
        out_.encode_ms_per_mp.push_back(double(j["encode_ms"]) / mp);
      }
    }
    buffer_.consume(buffer_.size());
  }

  websocket::stream<beast::tcp_stream> ws_;
  asio::steady_timer timer_;
  beast::flat_buffer buffer_;
  std::deque<std::string> queue_;
  uint16_t port_;
  int size_, index_;
  Samples& out_;
  Clock::time_point end_;
  glm::dvec3 center_{0.0};
  double radius_ = 1, angle_ = 0;
  bool center_ready_ = false;
  uint32_t version_ = 1;
  std::map<uint32_t, Clock::time_point> sent_;
};

struct ServeBenchArgs {
  std::vector<int> clients{1, 4, 16};
  double seconds = 10;
  int size = 1024;
  std::string data_dir = "bench-data";
};

}  // namespace

void add_serve_command(CLI::App& bench, Runner& run) {
  auto a = std::make_shared<ServeBenchArgs>();
  auto* sv =
      bench.add_subcommand("serve", "Loopback clients orbiting at 30 Hz against an in-process server (blobs 256^3)");
  sv->add_option("--clients", a->clients, "client counts to run, one after the other")->delimiter(',');
  sv->add_option("--seconds", a->seconds, "duration per client count");
  sv->add_option("--size", a->size, "square viewport in pixels");
  sv->add_option("--data-dir", a->data_dir, "where the generated volume is cached");
  sv->callback([a, &run] {
    run = [a] {
      fs::create_directories(a->data_dir);
      const fs::path vol = fs::path(a->data_dir) / "blobs_256x256x256.raw";
      if (!fs::exists(vol)) {
        GeneratorSpec g;
        g.kind = GeneratorKind::Blobs;
        g.dims = {256, 256, 256};
        generate_to_file(g, vol);
      }
      std::printf("%7s %9s %9s %9s %9s %10s %11s %11s %9s %8s\n", "clients", "int_p50", "int_p95", "fin_p50", "fin_p95",
                  "fps/client", "bytes/frame", "enc_ms/MP", "cpu_s", "rss_MiB");
      for (int n : a->clients) {
        ServerConfig cfg;
        cfg.port = 0;
        cfg.volumes = {vol};
        cfg.data_dirs = {a->data_dir};
        cfg.max_sessions = std::max(16, n);
        cfg.shader_dir = render::default_shader_dir();
        Server server(cfg);
        server.start();
        rusage before{};
        getrusage(RUSAGE_SELF, &before);
        Samples samples;
        asio::io_context ioc;
        const auto end =
            Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a->seconds));
        for (int i = 0; i < n; ++i)
          std::make_shared<BenchClient>(ioc, server.port(), a->size, i, samples, end)->start();
        ioc.run();
        rusage after{};
        getrusage(RUSAGE_SELF, &after);
        const double cpu =
            double(after.ru_utime.tv_sec - before.ru_utime.tv_sec + after.ru_stime.tv_sec - before.ru_stime.tv_sec) +
            double(after.ru_utime.tv_usec - before.ru_utime.tv_usec + after.ru_stime.tv_usec -
                   before.ru_stime.tv_usec) /
                1e6;
        std::printf("%7d %9.1f %9.1f %9.1f %9.1f %10.2f %11.0f %11.2f %9.1f %8.0f\n", n,
                    percentile(samples.interactive_ms, 0.5), percentile(samples.interactive_ms, 0.95),
                    percentile(samples.final_ms, 0.5), percentile(samples.final_ms, 0.95),
                    double(samples.frames) / a->seconds / n,
                    samples.frames ? double(samples.bytes) / samples.frames : 0.0,
                    percentile(samples.encode_ms_per_mp, 0.5), cpu, double(after.ru_maxrss) / 1024.0);
        std::fflush(stdout);
        server.stop();
      }
      std::printf(
          "latency: camera event sent -> frame received (ms), interactive and final (still) frames;\n"
          "cpu_s: process CPU seconds (server + clients) during the run; rss: peak of the process\n");
      return 0;
    };
  });
}

}  // namespace peakcast::bench
