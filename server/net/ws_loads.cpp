// What a viewer's messages need read from disk, on the loader pool, never on an io thread: a
// volume (with loading messages), a ray-texture PNG, and a pyramid's finest-level statistics.
#include <chrono>

#include <boost/asio/post.hpp>

#include "core/ray_texture_png.h"
#include "core/scene_error.h"
#include "net/rest_still.h"
#include "net/ws_session.h"
#include "session/limits.h"
#include "session/protocol.h"

namespace peakcast::net {

void WsSession::with_volume(const std::string& id, std::function<void(std::shared_ptr<VolumeEntry>)> then,
                            int64_t time) {
  if (auto e = app_.volumes.find_time(id, time)) return then(e);
  asio::post(app_.loader, [self = shared_from_this(), id, then = std::move(then), time] {
    std::shared_ptr<VolumeEntry> entry;
    std::string error;
    // The client hears how far the read is: the first percent, then at most every 100 ms, and the
    // end (a loading message of 1 comes before the welcome or volume message).
    auto last = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    auto progress = [&self, &id, &last](double fraction) {
      const auto now = std::chrono::steady_clock::now();
      if (fraction < 1 && now - last < std::chrono::milliseconds(100)) return;
      last = now;
      asio::post(self->ws_.get_executor(), [self, message = protocol::loading_message(id, fraction)]() mutable {
        if (!self->closing_) self->queue_text(std::move(message));
      });
    };
    std::string code = "volume_error";
    try {
      entry = self->app_.volumes.at_time(id, time, progress);
    } catch (const SceneError& e) {  // a time point past the series' last
      code = "bad_message";
      error = e.what();
    } catch (const std::exception& e) {
      error = e.what();
    }
    asio::post(self->ws_.get_executor(), [self, entry, error, code, then] {
      if (self->closing_) return;
      if (!error.empty()) {
        self->starting_ = false;
        return self->send_error(code, error);
      }
      self->guarded([&] { then(entry); });
    });
  });
}

void WsSession::open_volume(const std::string& id) {
  with_volume(id, [this](std::shared_ptr<VolumeEntry> entry) {
    session_->set_volume(entry);
    prepare_finest(entry);
    queue_text(protocol::volume_message(entry->info(true), session_->state_json()));
    app_.render.notify();
  });
}

void WsSession::step_time(int64_t time) {
  const std::string id = session_->volume_id();
  const uint64_t step = ++time_steps_;
  with_volume(
      id,
      [this, step](std::shared_ptr<VolumeEntry> entry) {
        if (step != time_steps_) return;  // a later step was asked while this one was read
        session_->set_time(entry);
        prepare_finest(entry);
        app_.render.notify();
        // The next time points, apart from the loader (a pick waits for no read-ahead).
        asio::post(app_.ahead, [self = shared_from_this(), id = entry->id, t = entry->time] {
          self->app_.volumes.read_ahead(id, t, limits::kTimeReadAhead);
        });
      },
      time);
}

void WsSession::with_png(const nlohmann::json& render, TextureThen then) {
  const bool png = render.is_object() && render.contains("ray_texture") && render["ray_texture"].is_object() &&
                   render["ray_texture"].contains("png");
  if (!png) return then(std::nullopt);
  paused_ = true;
  asio::post(app_.loader, [self = shared_from_this(), j = render["ray_texture"], then = std::move(then)] {
    std::shared_ptr<const RayTextureSpec> texture;
    std::string error;
    try {
      texture =
          load_ray_texture_png(std::make_shared<const RayTextureSpec>(parse_ray_texture(j)), self->app_.png_locator());
    } catch (const std::exception& e) {
      error = e.what();
    }
    asio::post(self->ws_.get_executor(), [self, texture, error, then] {
      self->paused_ = false;
      if (self->closing_) return;
      if (!error.empty()) {
        self->starting_ = false;  // a hello whose PNG failed may be sent again
        self->send_error("bad_message", error);
      } else {
        self->guarded([&] { then(texture); });
      }
      if (!self->closing_) self->read_when_allowed();
    });
  });
}

void WsSession::prepare_finest(const std::shared_ptr<VolumeEntry>& entry) {
  if (!entry->full) return;
  asio::post(app_.pyramid, [self = shared_from_this(), entry, session = session_] {
    try {
      auto statistics = VolumeStore::full_statistics(*entry, self->app_.stopping);
      session->set_full_statistics(entry, std::move(statistics));
      self->app_.render.notify();
    } catch (const std::exception& e) {  // the view stays at the level held, and says why
      asio::post(self->ws_.get_executor(), [self, message = without_volume_path(*entry, e.what())] {
        if (!self->closing_) self->send_error("volume_error", "the finest level cannot be drawn: " + message);
      });
    }
  });
}

}  // namespace peakcast::net
