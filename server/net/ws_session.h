// One WebSocket viewer: reads JSON messages (parse and validate only, then store the newest
// state in its Session), writes frames and text with one write in flight. A frame waiting to be
// written is replaced by a newer one (the older is dropped and released from flow control).
#pragma once

#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "net/app_context.h"
#include "net/beast.h"
#include "net/rest_routes.h"
#include "session/protocol.h"
#include "session/session.h"

namespace peakcast::net {

class WsSession : public FrameSink, public std::enable_shared_from_this<WsSession> {
 public:
  // `who.authorized`: the upgrade checked the token (or the server is open) and reserved this
  // session's slot in app.ws_sessions. Otherwise the client has kHandshakeTimeout to send a hello
  // with a valid token, and the slot is taken then. The session gives its slot back.
  WsSession(tcp::socket&& socket, AppContext& app, Principal who, std::shared_ptr<class ConnectionSlot> slot);
  ~WsSession() override;
  void run(Request upgrade);
  // Any thread: the upload `id` was deleted. A session viewing it is told (error volume_deleted)
  // and moves to the server's default volume, or closes when there is none.
  void volume_removed(const std::string& id);
  // Any thread: sends a close frame (going away) after what is queued; the server is stopping.
  void shut_down();

  // FrameSink: called from encode threads.
  void deliver_frame(std::vector<uint8_t> bytes, uint32_t frame_id, bool final, bool video) override;
  void deliver_text(std::string text) override;
  void deliver_stats(std::string text, uint32_t frame_id) override;

 private:
  struct Outgoing {
    bool binary = false;
    std::shared_ptr<const std::string> text;
    std::shared_ptr<const std::vector<uint8_t>> frame;
    uint32_t frame_id = 0;
    bool final = false;
    bool video = false;                // a video stream's frame: the next one refers to it, so it is never replaced
    std::optional<uint32_t> stats_of;  // a text: that frame's stats
  };
  void read();
  void on_message();
  // Runs fn on the strand, turning every exception into an error reply (nothing escapes a handler).
  void guarded(const std::function<void()>& fn);
  // Calls then(entry) on the strand once the volume is loaded (on the loader pool when needed).
  // `time`: that time point of a time series (VolumeStore::at_time).
  void with_volume(const std::string& id, std::function<void(std::shared_ptr<VolumeEntry>)> then, int64_t time = 0);
  void open_volume(const std::string& id);  // a volume message
  void step_time(int64_t time);             // a time message: then the next time points read ahead
  uint64_t time_steps_ = 0;                 // time messages handled: a step read late yields to a newer one
  // A render patch's ray-texture PNG is read on the loader pool, never on an io thread; no
  // further message is read until then(texture) has run, so a stroke sent after it applies to
  // it. then(nullopt) at once when the patch names no PNG (the session parses it inline).
  using TextureThen = std::function<void(std::optional<std::shared_ptr<const RayTextureSpec>>)>;
  void with_png(const nlohmann::json& render, TextureThen then);
  // A pyramid held coarser than its finest level: that level's statistics reduced on the loader
  // pool (once per volume), after which the session's final frames are followed by the finest.
  void prepare_finest(const std::shared_ptr<VolumeEntry>& entry);
  void start_session(const protocol::Hello& hello, std::shared_ptr<VolumeEntry> volume,
                     std::optional<std::shared_ptr<const RayTextureSpec>> texture);
  void handle(const std::string& text);
  // Probes run on the loader pool one at a time; one that arrives meanwhile waits, and a newer one
  // replaces it (the cursor moved on).
  void probe(const protocol::ProbeMsg& m);
  void send_error(const std::string& code, const std::string& message);
  void queue_text(std::string text);  // on the strand: in order with what this handler does next
  void enqueue(Outgoing out);
  void write_next();
  void arm_idle_timer();
  void arm_auth_timer();
  void read_when_allowed();  // the message rate: a fast sender is read later, never dropped
  void arm_write_timer();
  void close(websocket::close_code code, const std::string& reason);
  void release();

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  AppContext& app_;
  bool authorized_;
  Principal who_;
  bool counted_ = false, closing_ = false, writing_ = false, close_sent_ = false;
  websocket::close_code close_code_ = websocket::close_code::normal;
  std::string close_reason_;
  std::shared_ptr<Session> session_;
  bool starting_ = false;  // hello accepted, volume loading
  bool paused_ = false;    // a PNG is being read: the next message waits
  bool probing_ = false;
  std::optional<protocol::ProbeMsg> next_probe_;
  std::deque<Outgoing> queue_;
  uint32_t newest_frame_ = 0;  // the newest frame id queued (sent or waiting)
  asio::steady_timer idle_, pace_, write_timer_, auth_;
  std::shared_ptr<ConnectionSlot> slot_;
  double tokens_;  // message-rate bucket (limits::kMessageBurst at most)
  Clock::time_point tokens_at_;
};

}  // namespace peakcast::net
