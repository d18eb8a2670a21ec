// Video for interactive frames (docs/streaming.md): H.264, VP9 and AV1 through Debian's
// libavcodec, tuned for latency (no B-frames, no lookahead, one packet out per frame in), and a
// decoder for the benchmark and the tests. Built only with PEAKCAST_HAVE_VIDEO.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace peakcast::encode {

enum class VideoCodec { H264, VP9, AV1 };

// "h264", "vp9", "av1"; nullopt for anything else ("jpeg" is not a video codec).
std::optional<VideoCodec> video_codec_from_name(std::string_view name);
const char* to_string(VideoCodec codec);

// The wire codecs this process can encode: "jpeg" first, then each video codec whose encoder
// opened (a 64x64 trial, once per process; the NVIDIA encoders only where the driver answers).
const std::vector<std::string>& available_codecs();
bool codec_available(std::string_view name);

struct VideoSettings {
  VideoCodec codec = VideoCodec::H264;
  int width = 0, height = 0;  // the coded size: frames of another size are scaled to it
  int kbps = 8000;            // the bit-rate ceiling; one frame may take kbps / fps
  int quality = 70;           // today's JPEG scale (10..100), mapped onto the codec's CRF
  int fps = 30;               // the rate the budget is planned for
  int threads = 2;
  // The encoder's own (private) options over peakcast's, as "key=value;key=value" (libavcodec's
  // names: preset, crf, x264-params, cpu-used, ...). An encoder that lacks one, or refuses its
  // value, is not opened: the next for the codec is tried (h264_nvenc, then libx264), and the
  // error names the option when none opens. encoder_name() says which one did.
  std::string encoder_options;
};

struct VideoPacket {
  std::vector<uint8_t> bytes;  // one access unit (Annex B for H.264; a VP9 / AV1 frame)
  bool key = false;
};

// One session's encoder: stateful, used by one thread at a time, frames in display order.
class VideoEncoder {
 public:
  explicit VideoEncoder(const VideoSettings& settings);  // throws std::runtime_error
  ~VideoEncoder();
  VideoEncoder(const VideoEncoder&) = delete;
  VideoEncoder& operator=(const VideoEncoder&) = delete;

  // rgb: width*height*3, row 0 at the top. The packet of this frame (no encoder delay: an
  // encoder that held a frame back throws, which the tests catch).
  VideoPacket encode(const uint8_t* rgb, int width, int height, bool force_key);
  const VideoSettings& settings() const;
  const char* encoder_name() const;  // libavcodec's: libx264, libvpx-vp9, libsvtav1, h264_nvenc...

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// libavcodec's decoder: what the benchmark measures PSNR on, and the tests check packets with.
class VideoDecoder {
 public:
  explicit VideoDecoder(VideoCodec codec);
  ~VideoDecoder();
  VideoDecoder(const VideoDecoder&) = delete;
  VideoDecoder& operator=(const VideoDecoder&) = delete;
  // One packet in; the decoded picture as RGB (row 0 at the top). False when the packet gave no
  // picture (or failed: a delta frame without its reference).
  bool decode(const std::vector<uint8_t>& packet, std::vector<uint8_t>& rgb, int& width, int& height);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peakcast::encode
