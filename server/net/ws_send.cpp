// A viewer's send queue: frames and texts from encode threads and the strand, written one at a
// time; a newer frame replaces one waiting, an older one is dropped, and the stats of a frame
// older than the newest queued never go (net/frame_queue.h, docs/streaming.md "Key frames, acks
// and dropped frames").
#include <algorithm>
#include <chrono>

#include "net/frame_queue.h"
#include "net/ws_session.h"
#include "session/limits.h"
#include "session/protocol.h"

namespace peakcast::net {

// A write that does not finish in kWsWriteTimeout means a client that does not read: closed.
void WsSession::arm_write_timer() {
  write_timer_.expires_after(limits::kWsWriteTimeout);
  write_timer_.async_wait([weak = weak_from_this()](beast::error_code ec) {
    if (ec) return;  // the write finished
    if (auto self = weak.lock()) {
      self->app_.metrics.add("peakcast_ws_write_timeouts_total", "", 1);
      beast::get_lowest_layer(self->ws_).close();  // a close frame could not be written either
    }
  });
}

void WsSession::queue_text(std::string text) {
  Outgoing o;
  o.text = std::make_shared<const std::string>(std::move(text));
  enqueue(std::move(o));
}

void WsSession::deliver_frame(std::vector<uint8_t> bytes, uint32_t frame_id, bool final, bool video) {
  Outgoing o;
  o.binary = true;
  o.video = video;
  o.frame = std::make_shared<const std::vector<uint8_t>>(std::move(bytes));
  o.frame_id = frame_id;
  o.final = final;
  asio::post(ws_.get_executor(),
             [self = shared_from_this(), o = std::move(o)]() mutable { self->enqueue(std::move(o)); });
}

void WsSession::deliver_text(std::string text) {
  Outgoing o;
  o.text = std::make_shared<const std::string>(std::move(text));
  asio::post(ws_.get_executor(),
             [self = shared_from_this(), o = std::move(o)]() mutable { self->enqueue(std::move(o)); });
}

void WsSession::deliver_stats(std::string text, uint32_t frame_id) {
  Outgoing o;
  o.text = std::make_shared<const std::string>(std::move(text));
  o.stats_of = frame_id;
  asio::post(ws_.get_executor(),
             [self = shared_from_this(), o = std::move(o)]() mutable { self->enqueue(std::move(o)); });
}

void WsSession::enqueue(Outgoing out) {
  if (closing_) {
    if (out.binary && session_) session_->frame_dropped(out.frame_id);
    return;
  }
  if (out.binary) {
    // The newest frame replaces a frame still waiting (not the one being written); an older one
    // is dropped instead (net/frame_queue.h). The flow control before rendering (at most
    // kMaxFramesInFlight un-acknowledged) bounds what waits.
    // Stats of a frame older than the newest queued are dropped (below, and as they arrive).
    const FramePlacement p = place_frame(queue_, writing_ ? 1 : 0, out.frame_id, out.video);
    if (p.replace || p.drop) {
      if (session_) session_->frame_dropped(p.drop ? out.frame_id : queue_[*p.replace].frame_id);
      app_.metrics.add("peakcast_frames_dropped_total", "", 1);
      if (p.drop) return;
      queue_.erase(queue_.begin() + long(*p.replace));
    }
    newest_frame_ = std::max(newest_frame_, out.frame_id);
    // Stats already waiting for a frame now older than this one go with it.
    queue_.erase(
        std::remove_if(queue_.begin() + (writing_ ? 1 : 0), queue_.end(),
                       [&](const Outgoing& o) { return o.stats_of && stats_are_stale(*o.stats_of, newest_frame_); }),
        queue_.end());
  } else if (out.stats_of && stats_are_stale(*out.stats_of, newest_frame_)) {
    return;
  } else if (queue_.size() >= limits::kMaxQueuedTextMessages) {
    return close(websocket::close_code::policy_error, "client too slow");
  }
  queue_.push_back(std::move(out));
  if (!writing_) write_next();
}

void WsSession::write_next() {
  if (queue_.empty()) {
    if (closing_ && !close_sent_) {  // everything queued before the close has gone out
      close_sent_ = true;
      ws_.async_close(websocket::close_reason(close_code_, close_reason_),
                      [self = shared_from_this()](beast::error_code ec) {
                        if (ec) fail(ec, "ws close");
                      });
    }
    return;
  }
  writing_ = true;
  arm_write_timer();
  Outgoing& o = queue_.front();
  ws_.binary(o.binary);
  auto done = [self = shared_from_this()](beast::error_code ec, std::size_t bytes) {
    self->writing_ = false;
    self->write_timer_.cancel();
    if (ec) {
      self->queue_.clear();
      return fail(ec, "ws write");
    }
    Outgoing sent = std::move(self->queue_.front());
    self->queue_.pop_front();
    if (sent.binary) {
      const char* kind = sent.final ? "kind=\"final\"" : "kind=\"interactive\"";
      self->app_.metrics.add("peakcast_frames_sent_total", kind, 1);
      self->app_.metrics.add("peakcast_bytes_sent_total", "", double(bytes));
      const auto h = protocol::decode_frame_header(sent.frame->data(), sent.frame->size());
      const double now_us =
          double(std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch()).count());
      self->app_.metrics.observe("peakcast_input_to_sent_ms", kind, (now_us - double(h.t_input_us)) / 1000.0);
    }
    self->write_next();
  };
  if (o.binary)
    ws_.async_write(asio::buffer(*o.frame), std::move(done));
  else
    ws_.async_write(asio::buffer(*o.text), std::move(done));
}

}  // namespace peakcast::net
