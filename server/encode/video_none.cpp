// A build without libavcodec (PEAKCAST_WITH_VIDEO found nothing): frames go out as JPEG only.
#include <stdexcept>

#include "encode/video.h"

namespace peakcast::encode {

std::optional<VideoCodec> video_codec_from_name(std::string_view name) {
  if (name == "h264") return VideoCodec::H264;
  if (name == "vp9") return VideoCodec::VP9;
  if (name == "av1") return VideoCodec::AV1;
  return std::nullopt;
}

const char* to_string(VideoCodec c) { return c == VideoCodec::H264 ? "h264" : c == VideoCodec::VP9 ? "vp9" : "av1"; }

const std::vector<std::string>& available_codecs() {
  static const std::vector<std::string> codecs{"jpeg"};
  return codecs;
}

bool codec_available(std::string_view name) { return name == "jpeg"; }

struct VideoEncoder::Impl {};
VideoEncoder::VideoEncoder(const VideoSettings&) {
  throw std::runtime_error("video: this build has no libavcodec (configure with libavcodec-dev installed)");
}
VideoEncoder::~VideoEncoder() = default;
VideoPacket VideoEncoder::encode(const uint8_t*, int, int, bool) { return {}; }
const VideoSettings& VideoEncoder::settings() const { throw std::logic_error("video: none"); }
const char* VideoEncoder::encoder_name() const { return "none"; }

struct VideoDecoder::Impl {};
VideoDecoder::VideoDecoder(VideoCodec) {
  throw std::runtime_error("video: this build has no libavcodec (configure with libavcodec-dev installed)");
}
VideoDecoder::~VideoDecoder() = default;
bool VideoDecoder::decode(const std::vector<uint8_t>&, std::vector<uint8_t>&, int&, int&) { return false; }

}  // namespace peakcast::encode
