#include "session/frame_encoder.h"

#include <bit>

#include "encode/png.h"

namespace peakcast {
namespace {

uint64_t micros(Clock::time_point t) {
  return uint64_t(std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count());
}

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

}  // namespace

std::vector<uint8_t> encode_image(encode::JpegEncoder& enc, const std::vector<uint8_t>& rgb, int width, int height,
                                  bool png, int quality, encode::Subsampling sub) {
  return png ? encode::encode_png(rgb.data(), width, height) : enc.encode(rgb.data(), width, height, quality, sub);
}

namespace {

// Encodes (unless `video` holds the frame already) and hands the frame and its stats to the sink.
void send_viewer_frame(encode::JpegEncoder& enc, const RenderedFrame& f, std::optional<VideoFrameOut> video,
                       Clock::time_point t0, FrameSink& sink, Metrics& metrics, nlohmann::json stats) {
  const FrameJob& job = f.job;
  const bool png = job.final && job.quality.final_png;
  const int q = job.final ? job.quality.final_quality : job.quality.interactive_quality;
  std::vector<uint8_t> bytes = video ? std::move(video->packet.bytes)
                                     : encode_image(enc, f.rgb, f.width, f.height, png, q,
                                                    job.final ? encode::Subsampling::S444 : encode::Subsampling::S420);
  const auto encoded = Clock::now();
  const char* kind = job.final ? "kind=\"final\"" : video ? "kind=\"video\"" : "kind=\"interactive\"";
  metrics.observe("peakcast_encode_ms", kind, ms_between(t0, encoded));
  protocol::FrameHeader h;
  h.frame_id = job.frame_id;
  h.flags = (job.final ? protocol::FrameHeader::kFinal : protocol::FrameHeader::kInteractive) |
            (png ? protocol::FrameHeader::kPng : 0u) | (video ? protocol::FrameHeader::kVideo : 0u) |
            (video && video->packet.key ? protocol::FrameHeader::kKey : 0u);
  h.camera_version = job.camera_version;
  h.tf_version = job.tf_version;
  h.render_version = job.render_version;
  h.width = uint32_t(video ? video->width : f.width);
  h.height = uint32_t(video ? video->height : f.height);
  h.quality = png ? 100u : uint32_t(q);
  stats["codec"] = video ? encode::to_string(job.video_settings.codec) : png ? "png" : "jpeg";
  if (video) {
    stats["kbps"] = video->kbps;
    stats["key"] = video->packet.key;
    stats["encoder"] = video->encoder;
  }
  h.t_input_us = micros(job.input_time);
  h.t_render_done_us = micros(f.rendered);
  h.t_encode_done_us = micros(encoded);
  const size_t image_bytes = bytes.size();
  sink.deliver_frame(protocol::encode_frame(h, bytes), job.frame_id, job.final, bool(video));
  sink.deliver_stats(
      protocol::stats_message(job.frame_id, job.final, f.width, f.height, stats, ms_between(t0, encoded), image_bytes),
      job.frame_id);
}

}  // namespace

void encode_viewer_frame(encode::JpegEncoder& enc, const RenderedFrame& f, FrameSink& sink, Metrics& metrics) {
  const auto t0 = Clock::now();
  if (!f.job.video) return send_viewer_frame(enc, f, std::nullopt, t0, sink, metrics, f.stats);
  // A video frame goes to the sink in its stream's turn, so the wire has the frames in the order
  // they were encoded.
  f.job.video->encode(f.video_ticket, f.job.video_settings, f.rgb.data(), f.width, f.height,
                      [&](std::optional<VideoFrameOut> video, const std::string& error) {
                        nlohmann::json stats = f.stats;
                        if (!video) {  // this frame goes out as JPEG; the stream's next frame is a key frame
                          metrics.add("peakcast_video_failures_total", "", 1);
                          stats["warnings"].push_back("video encode failed, this frame sent as JPEG: " + error);
                        }
                        send_viewer_frame(enc, f, std::move(video), t0, sink, metrics, std::move(stats));
                      });
}

void deliver_refined_frame(FrameSink& sink, uint32_t frame_id, const FrameJob& job, StillResult r) {
  const bool png = r.content_type == "image/png";
  protocol::FrameHeader h;
  h.frame_id = frame_id;
  h.flags = protocol::FrameHeader::kFinal | (png ? protocol::FrameHeader::kPng : 0u);
  h.camera_version = job.camera_version;
  h.tf_version = job.tf_version;
  h.render_version = job.render_version;
  h.width = uint32_t(r.width);
  h.height = uint32_t(r.height);
  h.quality = png ? 100u : uint32_t(job.quality.final_quality);
  h.t_input_us = micros(job.input_time);
  h.t_render_done_us = h.t_encode_done_us = micros(Clock::now());
  const nlohmann::json stats = {{"render_ms", r.render_ms},
                                {"variant", r.variant},
                                {"codec", png ? "png" : "jpeg"},
                                {"level", 0},
                                {"bricks", r.bricks}};
  const size_t bytes = r.bytes.size();
  sink.deliver_frame(protocol::encode_frame(h, r.bytes), frame_id, true, false);
  sink.deliver_stats(protocol::stats_message(frame_id, true, r.width, r.height, stats, r.encode_ms, bytes), frame_id);
}

void encode_still(encode::JpegEncoder& enc, StillWork& w, Metrics& metrics) {
  StillResult r;
  const auto t0 = Clock::now();
  try {
    if (w.job.raw_float) {  // the renderer's own numbers: colour over the background, and opacity
      static_assert(std::endian::native == std::endian::little, "format=float is sent little-endian");
      const auto* f = reinterpret_cast<const uint8_t*>(w.image.rgba.data());
      r.bytes.assign(f, f + w.image.rgba.size() * sizeof(float));
    } else if (w.job.rgba) {
      const glm::vec3 bg(w.job.scene.scene.background);
      const float background[3] = {bg.x, bg.y, bg.z};
      const auto rgba = encode::to_rgba8_without_background(w.image, background);
      r.bytes = encode::encode_png(rgba.data(), w.image.width, w.image.height, 4);
    } else {
      auto rgb = encode::to_rgb8(w.image);
      r.bytes = w.job.raw_rgb ? std::move(rgb)
                              : encode_image(enc, rgb, w.image.width, w.image.height, w.job.png, w.job.quality,
                                             encode::Subsampling::S444);
    }
  } catch (const std::exception& e) {
    r.error = e.what();
    r.error_code = "encode_failed";
    metrics.add("peakcast_stills_total", "outcome=\"failed\"", 1);
    return w.job.done(std::move(r));
  }
  r.content_type = w.job.raw_rgb || w.job.raw_float ? "application/octet-stream"
                   : w.job.png                      ? "image/png"
                                                    : "image/jpeg";
  r.width = w.image.width;
  r.height = w.image.height;
  r.encode_ms = ms_between(t0, Clock::now());
  r.render_ms = w.render_ms;
  r.wait_ms = ms_between(w.queued, w.started);
  r.samples_per_ray = w.rays_hit ? w.samples_total / double(w.rays_hit) : 0.0;
  r.bands = w.bands;
  r.bricks = w.by_bricks() ? w.bands : 0;
  r.variant = w.variant;
  r.warnings = w.warnings;
  metrics.add("peakcast_stills_total", "outcome=\"done\"", 1);
  w.job.done(std::move(r));
}

}  // namespace peakcast
