#include "bench/soak_client.h"

#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <memory>
#include <random>

#include "bench/bench_util.h"
#include "session/protocol.h"

namespace peakcast::bench {

using namespace peakcast::net;
using nlohmann::json;
using Clock = SoakClock;
using Kind = SoakClientKind;

void SoakStats::latency(SoakClock::time_point sent_at, SoakClock::time_point now) {
  const size_t w = size_t(std::chrono::duration<double>(sent_at - start).count() / window_s);
  std::lock_guard lock(m);
  if (latency_ms.size() <= w) latency_ms.resize(w + 1);
  latency_ms[w].push_back(ms_between(sent_at, now));
}

namespace {

// One WebSocket client. Viewers and the non-acking client run until `end`; the vanisher
// reconnects after each abrupt close until `end`.
class SoakClient : public std::enable_shared_from_this<SoakClient> {
 public:
  SoakClient(asio::io_context& ioc, uint16_t port, Kind kind, int size, unsigned seed, SoakStats& out,
             Clock::time_point end)
      : ioc_(ioc),
        ws_(std::make_unique<Ws>(asio::make_strand(ioc))),
        timer_(ioc),
        port_(port),
        kind_(kind),
        size_(size),
        rng_(seed),
        out_(out),
        end_(end) {}

  void start() {
    auto self = shared_from_this();
    beast::get_lowest_layer(*ws_).async_connect(
        tcp::endpoint(asio::ip::make_address("127.0.0.1"), port_), [self](beast::error_code ec) {
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
    ws_->async_write(asio::buffer(queue_.front()),
                     [self = shared_from_this(), gen = gen_](beast::error_code ec, std::size_t) {
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
      self->strokes_ = 0;  // a new session has no ray texture
      self->vanish_at_ =
          Clock::now() + std::chrono::milliseconds(std::uniform_int_distribution<int>(100, 800)(self->rng_));
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
      send(json{{"type", "camera"}, {"camera", {{"eye", {e[0], e[1], e[2]}}, {"center", center_}, {"up", {0, 1, 0}}}}}
               .dump());
      sent_[++camera_version_] = now;
    } else if (r < 0.75) {
      const double a = u(rng_);
      send(json{
          {"type", "tf"},
          {"version", ++tf_version_},
          {"tf",
           {{"points",
             {{lo_, 0, 0, 0, 0}, {lo_ + (hi_ - lo_) * (0.2 + 0.6 * u(rng_)), 1, 0.5, 0.2, a}, {hi_, 1, 1, 1, a}}}}}}
               .dump());
    } else if (r < 0.85) {
      static const json patches[] = {{{"shading", true}},           {{"shading", false}},
                                     {{"filter", "tricubic"}},      {{"filter", "trilinear"}},
                                     {{"classification", "peaks"}}, {{"classification", "post"}}};
      send(json{{"type", "render"}, {"render", patches[std::uniform_int_distribution<size_t>(0, 5)(rng_)]}}.dump());
    } else if (r < 0.95) {
      send(json{{"type", "ping"}, {"id", "p" + std::to_string(++pings_)}}.dump());
      expect();
    } else {
      // A ray-texture stroke (proto/messages.md), answered by a stroke_ack; the first one sets
      // up a view-aligned texture on this connection.
      if (strokes_ == 0)
        send(json{{"type", "render"}, {"render", {{"ray_texture", {{"mapping", "view"}, {"size", {128, 128}}}}}}}
                 .dump());
      send(json{{"type", "stroke"},
                {"seq", ++strokes_},
                {"stroke",
                 {{"channel", "step"},
                  {"center", {u(rng_), u(rng_)}},
                  {"radius", 0.05},
                  {"falloff", 0.5},
                  {"value", 2.0},
                  {"mode", "set"},
                  {"level", strokes_ % 3}}}}
               .dump());
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
    } else if (type == "pong" || type == "stroke_ack") {
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
  uint32_t strokes_ = 0;  // on this connection's ray texture
  unsigned gen_ = 0;      // connection number: handlers of a vanished connection do nothing
  std::map<uint32_t, Clock::time_point> sent_;
};

}  // namespace

void start_soak_client(asio::io_context& ioc, uint16_t port, SoakClientKind kind, int size, unsigned seed,
                       SoakStats& out, SoakClock::time_point end) {
  std::make_shared<SoakClient>(ioc, port, kind, size, seed, out, end)->start();
}

}  // namespace peakcast::bench
