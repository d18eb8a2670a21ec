// Where a frame goes in a viewer's send queue (docs/streaming.md, "Key frames, acks and dropped
// frames"): the newest frame replaces one still waiting, so a slow link shows the newest picture
// rather than a backlog. Frames reach the queue in the order their encodes finish, which is not
// always the order they were rendered in (encode threads, a refinement's still thread): an older
// frame arriving after a newer one must not replace it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

namespace peakcast {

struct FramePlacement {
  std::optional<size_t> replace;  // the waiting frame to drop (never sent) before queueing this one
  bool drop = false;              // this frame is older than one waiting: drop it, queue nothing
};

// `queue`'s entries have .binary, .video and .frame_id; those before `first_waiting` are being
// written. A video frame is never replaced nor dropped (the next one is coded against it); it
// waits behind a newer frame, which the client draws over it anyway (it draws newer ids only).
template <typename Queue>
FramePlacement place_frame(const Queue& queue, size_t first_waiting, uint32_t frame_id, bool video) {
  FramePlacement p;
  for (size_t k = first_waiting; k < queue.size(); ++k) {
    const auto& waiting = queue[k];
    if (!waiting.binary || waiting.video) continue;
    if (waiting.frame_id > frame_id) {
      p.drop = !video;
    } else {
      p.replace = k;
    }
    break;
  }
  return p;
}

// A frame's stats message goes only while no newer frame has been queued (`newest`, sent or
// waiting): the stats of a frame dropped, replaced or overtaken never reach the client.
inline bool stats_are_stale(uint32_t stats_frame, uint32_t newest) { return stats_frame < newest; }

}  // namespace peakcast
