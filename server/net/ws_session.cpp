#include "net/ws_session.h"

#include <chrono>

#include "core/ray_texture_png.h"
#include "encode/video.h"
#include "net/connection_slot.h"
#include "render/variant.h"
#include "session/protocol.h"

namespace peakcast::net {

WsSession::WsSession(tcp::socket&& socket, AppContext& app, Principal who, std::shared_ptr<ConnectionSlot> slot)
    : ws_(std::move(socket)),
      app_(app),
      authorized_(who.authorized),
      who_(std::move(who)),
      idle_(ws_.get_executor()),
      pace_(ws_.get_executor()),
      write_timer_(ws_.get_executor()),
      auth_(ws_.get_executor()),
      slot_(std::move(slot)),
      tokens_(limits::kMessageBurst),
      tokens_at_(Clock::now()) {}

WsSession::~WsSession() { release(); }

// The connection is over: free its session slot now, not when the last frame in flight lets go
// of this object.
void WsSession::release() {
  if (session_) app_.render.remove_session(session_->id());
  if (counted_) app_.ws_sessions.release();
  counted_ = false;
}

void WsSession::shut_down() {
  asio::post(ws_.get_executor(), [self = shared_from_this()] {
    self->close(websocket::close_code::going_away, "the server is shutting down");
  });
}

void WsSession::run(Request upgrade) {
  counted_ = authorized_;  // then the slot was reserved by the upgrade (SessionRegistry::try_reserve)
  app_.ws_sessions.track(shared_from_this());
  ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
  ws_.read_message_max(limits::kMaxWsReadBytes);
  ws_.set_option(websocket::stream_base::decorator(
      [](websocket::response_type& res) { res.set(http::field::server, "peakcast"); }));
  auto req = std::make_shared<Request>(std::move(upgrade));
  ws_.async_accept(*req, [self = shared_from_this(), req](beast::error_code ec) {
    if (ec) return fail(ec, "ws accept");
    self->arm_idle_timer();
    if (!self->authorized_) self->arm_auth_timer();
    self->read();
  });
}

// An unauthenticated socket holds no session slot, and only this long: messages before a valid
// hello (pings) do not extend it.
void WsSession::arm_auth_timer() {
  auth_.expires_after(limits::kHandshakeTimeout);
  auth_.async_wait([weak = weak_from_this()](beast::error_code ec) {
    if (ec) return;
    auto self = weak.lock();
    if (!self || self->authorized_) return;
    self->send_error("unauthorized",
                     "no hello with a valid token within " + std::to_string(limits::kHandshakeTimeout.count()) + " s");
    self->close(websocket::close_code::policy_error, "unauthorized");
  });
}

void WsSession::volume_removed(const std::string& id) {
  asio::post(ws_.get_executor(), [self = shared_from_this(), id] {
    if (!self->session_ || self->closing_ || self->session_->volume_id() != id) return;
    const std::string fallback = self->app_.volumes.default_id();
    self->send_error("volume_deleted", "the volume '" + id + "' was deleted" +
                                           (fallback.empty() ? std::string() : "; showing '" + fallback + "'"));
    if (fallback.empty() || fallback == id) return self->close(websocket::close_code::going_away, "volume deleted");
    self->guarded([&] { self->open_volume(fallback); });
  });
}

void WsSession::arm_idle_timer() {
  idle_.expires_after(app_.config.idle_timeout);
  idle_.async_wait([weak = weak_from_this()](beast::error_code ec) {
    if (ec) return;  // re-armed or closed
    if (auto self = weak.lock()) self->close(websocket::close_code::going_away, "idle timeout");
  });
}

void WsSession::read() {
  ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
    if (ec == websocket::error::message_too_big) {  // Beast has already closed with 1009
      self->idle_.cancel();
      self->pace_.cancel();
      self->auth_.cancel();
      self->release();
      return;
    }
    if (ec) {
      self->idle_.cancel();
      self->pace_.cancel();
      self->auth_.cancel();
      self->release();
      return fail(ec, "ws read");
    }
    self->on_message();
  });
}

void WsSession::on_message() {
  arm_idle_timer();
  if (!ws_.got_text()) {
    buffer_.consume(buffer_.size());
    send_error("bad_message", "binary messages are not accepted; send JSON text");
  } else {
    const std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    guarded([&] { handle(text); });
  }
  if (!closing_ && !paused_) read_when_allowed();
}

// A token bucket: kMessageBurst messages at once, kMaxMessagesPerSecond sustained. Past it the
// next read waits, so TCP backpressure slows the sender; no message is dropped, and a flood of
// edits costs the io thread no more than the rate.
void WsSession::read_when_allowed() {
  const auto now = Clock::now();
  tokens_ = std::min(limits::kMessageBurst,
                     tokens_ + std::chrono::duration<double>(now - tokens_at_).count() * limits::kMaxMessagesPerSecond);
  tokens_at_ = now;
  if (tokens_ >= 1.0) {
    tokens_ -= 1.0;
    return read();
  }
  app_.metrics.add("peakcast_ws_paced_total", "", 1);
  pace_.expires_after(std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>((1.0 - tokens_) / limits::kMaxMessagesPerSecond)));
  pace_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (ec || self->closing_) return;
    self->read_when_allowed();
  });
}

void WsSession::guarded(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const protocol::ProtocolError& e) {
    send_error(e.code, e.what());
  } catch (const VolumeError& e) {
    send_error("volume_error", e.what());
  } catch (const std::exception& e) {  // nothing escapes the handler
    send_error("internal", e.what());
  }
}

void WsSession::handle(const std::string& text) {
  using namespace protocol;
  ClientMessage msg = parse_client_message(text);
  if (auto* ping = std::get_if<PingMsg>(&msg)) {
    return queue_text(pong_message(ping->id));
  }
  if (auto* hello = std::get_if<Hello>(&msg)) {
    if (session_) throw ProtocolError("bad_message", "hello: the session has already started");
    if (!authorized_) {
      Principal who = app_.access.who(hello->token);
      if (!who.authorized) {
        send_error("unauthorized", "missing or wrong token");
        return close(websocket::close_code::policy_error, "unauthorized");
      }
      // The slot is taken now that the token is checked (none before: see arm_auth_timer).
      if (!app_.ws_sessions.try_reserve()) {
        send_error("session_limit", "the server holds its maximum of " + std::to_string(app_.config.max_sessions) +
                                        " sessions; try again later");
        return close(websocket::close_code::try_again_later, "session limit");
      }
      counted_ = true;
      authorized_ = true;
      who_ = std::move(who);
      auth_.cancel();
    }
    const std::string vid = hello->volume.empty() ? app_.volumes.default_id() : hello->volume;
    if (vid.empty()) throw ProtocolError("volume_error", "no volume given and the server has none loaded");
    if (starting_) throw ProtocolError("bad_message", "hello: already starting");
    starting_ = true;
    const nlohmann::json render = hello->state.render ? *hello->state.render : nlohmann::json();
    with_png(render, [this, hello = *hello, vid](std::optional<std::shared_ptr<const RayTextureSpec>> texture) {
      with_volume(
          vid,
          [this, hello, texture](std::shared_ptr<VolumeEntry> volume) {
            starting_ = false;
            start_session(hello, std::move(volume), texture);
          },
          hello.state.time);
    });
    return;
  }
  if (!session_) throw ProtocolError("no_session", "send hello first");
  std::visit(
      [&](auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, CameraMsg>) session_->set_camera(m.camera);
        if constexpr (std::is_same_v<T, TfMsg>) session_->set_tf(m.tf, m.opacity_unit, m.version);
        if constexpr (std::is_same_v<T, RenderMsg>) {
          with_png(m.render, [this, render = m.render](std::optional<std::shared_ptr<const RayTextureSpec>> texture) {
            session_->merge_render(render, texture);
            app_.render.notify();
          });
        }
        if constexpr (std::is_same_v<T, QualityMsg>) session_->set_quality(m, app_.config.max_kbps);
        if constexpr (std::is_same_v<T, KeyframeMsg>) session_->request_key_frame();
        if constexpr (std::is_same_v<T, ViewportMsg>) session_->set_viewport(m.viewport);
        if constexpr (std::is_same_v<T, AckMsg>) session_->ack(m.frame);
        if constexpr (std::is_same_v<T, ProbeMsg>) probe(m);
        if constexpr (std::is_same_v<T, StrokeMsg>)
          queue_text(stroke_ack_message(m.seq, session_->add_stroke(m.stroke)));
        if constexpr (std::is_same_v<T, VolumeMsg>) open_volume(m.volume);
        if constexpr (std::is_same_v<T, TimeMsg>) step_time(m.time);
      },
      msg);
  app_.render.notify();
}

void WsSession::start_session(const protocol::Hello& hello, std::shared_ptr<VolumeEntry> volume,
                              std::optional<std::shared_ptr<const RayTextureSpec>> texture) {
  auto session =
      std::make_shared<Session>("s" + std::to_string(app_.next_session++), weak_from_this(), app_.png_locator());
  protocol::QualityMsg start_rate;  // a video stream starts at the server's ceiling
  start_rate.kbps = app_.config.max_kbps;
  session->set_quality(start_rate);
  session->start(volume, hello.viewport, hello.state, texture);
  session_ = session;
  prepare_finest(volume);
  nlohmann::json vols = nlohmann::json::array();
  for (const auto& v : app_.volumes.listing()) vols.push_back(v);
  protocol::Welcome welcome;
  welcome.session = session_->id();
  welcome.volume = volume->info(true);
  welcome.volumes = vols;
  welcome.state = session_->state_json();
  welcome.capabilities = render::capabilities();
  welcome.capabilities["codecs"] = encode::available_codecs();  // interactive frames: quality.codec
  welcome.gl_renderer = app_.render.gl_renderer();
  welcome.backend = app_.render.backend();
  welcome.limits = {{"max_message_bytes", limits::kMaxWsMessageBytes},
                    {"max_viewport_side", limits::kMaxViewportSide},
                    {"max_viewport_pixels", limits::kMaxViewportPixels},
                    {"max_frames_in_flight", limits::kMaxFramesInFlight},
                    {"max_tf_points", kMaxTfPoints},
                    {"idle_timeout_s", app_.config.idle_timeout.count()},
                    {"still_delay_ms", limits::kStillDelay.count()},
                    {"max_fps", app_.config.max_fps},
                    {"max_kbps", app_.config.max_kbps}};
  queue_text(protocol::welcome_message(welcome));
  app_.render.add_session(session_);
}

void WsSession::send_error(const std::string& code, const std::string& message) {
  app_.metrics.add("peakcast_ws_errors_total", "code=\"" + code + "\"", 1);
  queue_text(protocol::error_message(code, message));
}

void WsSession::close(websocket::close_code code, const std::string& reason) {
  if (closing_) return;
  closing_ = true;
  close_code_ = code;
  close_reason_ = reason;
  idle_.cancel();
  pace_.cancel();
  auth_.cancel();
  if (session_) app_.render.remove_session(session_->id());
  // Frames still queued are dropped; text (the error that explains the close) is sent first.
  for (auto it = queue_.begin() + (writing_ ? 1 : 0); it != queue_.end();) {
    if (it->binary) {
      if (session_) session_->frame_dropped(it->frame_id);
      it = queue_.erase(it);
    } else {
      ++it;
    }
  }
  if (!writing_) write_next();
}

}  // namespace peakcast::net
