// One session's video stream (docs/streaming.md): its encoder, the key-frame rules, and the
// order frames are encoded in. Frames are rendered on the render thread and encoded on any
// encode thread; inter-frame coding needs them encoded one at a time in the order rendered,
// so the render thread takes a ticket per frame and the encode threads serve tickets in order.
//
// Key frames: the first frame, a frame after the settings changed (codec, coded size, bit rate,
// quality: a new encoder), a frame after the client asked (it lost or could not decode one), and
// a frame after one of this stream's frames failed to encode.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "encode/video.h"

namespace peakcast {

struct VideoFrameOut {
  encode::VideoPacket packet;
  int width = 0, height = 0;  // the coded size
  double kbps = 0;            // the stream's rate over the last second, this frame included
  const char* encoder = "";
};

class VideoChannel {
 public:
  // Render thread, in the order frames are rendered: this frame's place in line.
  uint64_t take_ticket();
  // Encode thread: waits for the frames before this ticket, then encodes. Always serves the
  // ticket (a failed encode returns nullopt with `error` set, and the next frame is a key frame).
  std::optional<VideoFrameOut> encode(uint64_t ticket, const encode::VideoSettings& settings, const uint8_t* rgb,
                                      int width, int height, std::string& error);
  // The same, and `then` hands the frame on (to the session's send queue) before the next ticket's
  // turn: frames reach the wire in the order rendered, or a delta frame could arrive before the key
  // frame it refers to. `then` gets the frame, or nullopt and the error.
  using Then = std::function<void(std::optional<VideoFrameOut>, const std::string& error)>;
  void encode(uint64_t ticket, const encode::VideoSettings& settings, const uint8_t* rgb, int width, int height,
              const Then& then);
  void request_key_frame();  // the client's keyframe message

  // For the tests: encoders opened so far (each new one starts with a key frame).
  int encoders_opened() const;

 private:
  // Tickets and key-frame requests never wait for an encode (the render thread takes tickets).
  std::atomic<uint64_t> next_ticket_{0};
  std::atomic<bool> key_wanted_{false};
  std::atomic<int> opened_{0};
  std::mutex m_;  // the encoder, whose turn it is, the last second's packets
  std::condition_variable turn_;
  uint64_t serving_ = 0;
  std::unique_ptr<encode::VideoEncoder> encoder_;
  encode::VideoSettings current_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, size_t>> sent_;  // the last second's packets
};

// The coded size of a video stream for a view of width x height at an interactive scale: even
// (4:2:0), at least 16 x 16.
std::pair<int, int> video_coded_size(int width, int height, double interactive_scale);

}  // namespace peakcast
