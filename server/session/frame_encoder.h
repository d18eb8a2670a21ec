// Frame encoding on the encode pool (docs/architecture.md): a viewer's frame becomes JPEG (or
// PNG for a final frame when asked) behind the binary frame header, followed by its stats
// message; a still becomes the REST response's image. One image encoder serves both.
#pragma once

#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/image.h"
#include "core/metrics.h"
#include "encode/jpeg.h"
#include "session/scheduler.h"
#include "session/session.h"

namespace peakcast {

// rgb: width*height*3, row 0 at the top.
std::vector<uint8_t> encode_image(encode::JpegEncoder& enc, const std::vector<uint8_t>& rgb, int width, int height,
                                  bool png, int quality, encode::Subsampling sub);

struct RenderedFrame {
  FrameJob job;
  std::vector<uint8_t> rgb;  // row 0 at the top
  int width = 0, height = 0;
  nlohmann::json stats;  // RenderStats' JSON form
  Clock::time_point rendered;
  uint64_t video_ticket = 0;  // a video frame's place in its stream (VideoChannel::take_ticket)
};

// Encodes and hands the frame and its stats to the sink. Encode thread.
void encode_viewer_frame(encode::JpegEncoder& enc, const RenderedFrame& frame, FrameSink& sink, Metrics& metrics);

// A final frame of a pyramid's finest level (FrameJob::refine), encoded as a still: to the
// viewer as a final frame with the versions of `job`, and its stats (level 0, bricks).
void deliver_refined_frame(FrameSink& sink, uint32_t frame_id, const FrameJob& job, StillResult r);

// Encodes a finished still and answers its job. Encode thread.
void encode_still(encode::JpegEncoder& enc, StillWork& still, Metrics& metrics);

}  // namespace peakcast
