// A viewer's probes (proto/messages.md, "Probes"): the CPU reference ray under a pixel, on the
// loader pool, one at a time per connection; a probe arriving meanwhile waits, a newer replaces it.
#include <stdexcept>

#include <boost/asio/post.hpp>

#include "net/ws_session.h"
#include "reference/reference_renderer.h"
#include "session/protocol.h"

namespace peakcast::net {

void WsSession::probe(const protocol::ProbeMsg& m) {
  if (probing_) {
    next_probe_ = m;
    return;
  }
  probing_ = true;
  auto [volume, scene] = session_->view();
  asio::post(app_.loader, [self = shared_from_this(), m, volume, scene = std::move(scene)] {
    std::string answer, error;
    try {
      if (self->app_.config.ranks > 1)  // rank 0 holds no voxels (checked before any read)
        throw std::invalid_argument("probing needs the volume's voxels; under mpirun they live in the ranks' bricks");
      const auto p = reference::probe_reference(*volume->volume, scene, m.x, m.y, reference::parse_probe_pick(m.pick));
      answer = protocol::probe_message(
          m.id, protocol::probe_json(p.hit, p.position, p.value, p.distance, p.opacity, reference::to_string(p.pick)));
    } catch (const std::exception& e) {
      error = std::string("probe: ") + e.what();
    }
    asio::post(self->ws_.get_executor(), [self, answer, error] {
      self->probing_ = false;
      if (self->closing_) return;
      if (!error.empty())
        self->send_error("bad_message", error);
      else
        self->queue_text(answer);
      if (auto next = std::exchange(self->next_probe_, std::nullopt)) self->guarded([&] { self->probe(*next); });
    });
  });
}

}  // namespace peakcast::net
