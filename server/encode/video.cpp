#include "encode/video.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "encode/yuv420.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace peakcast::encode {
namespace {

struct CodecContextFree {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct FrameFree {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct PacketFree {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct SwsFree {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};
using ContextPtr = std::unique_ptr<AVCodecContext, CodecContextFree>;
using FramePtr = std::unique_ptr<AVFrame, FrameFree>;
using PacketPtr = std::unique_ptr<AVPacket, PacketFree>;
using SwsPtr = std::unique_ptr<SwsContext, SwsFree>;

std::string av_error(int err) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(err, buf, sizeof buf);
  return buf;
}

// The encoders tried for a codec, best first: the GPU's where the driver answers, then software.
std::vector<const char*> encoder_names(VideoCodec c) {
  switch (c) {
    case VideoCodec::H264: return {"h264_nvenc", "libx264"};
    case VideoCodec::VP9: return {"libvpx-vp9"};
    // Not libsvtav1: SVT-AV1 1.4 (Debian 12) calls its low-delay mode a work in progress, and an
    // encoder opened with it hung in avcodec_receive_packet here after the first frames.
    case VideoCodec::AV1: return {"av1_nvenc", "libaom-av1"};
  }
  return {};
}

// Today's JPEG quality (10..100) onto a CRF: q70 -> about JPEG q70's PSNR on the reference
// volume, q95 -> near transparent, q10 -> the coarsest useful. libx264: CRF 25.5 at q70, with the
// chroma offset below (measured, docs/streaming.md); NVENC's CQ keeps x264's usual 23 at q70 (no
// chroma offset there, and not measured: no NVENC block on the GPU hosts lent so far); VP9 and
// AV1: 25.
double crf_for(const std::string& encoder, VideoCodec c, int quality) {
  const double q = std::clamp(quality, 10, 100);
  if (encoder == "libx264") return std::clamp(53.5 - 0.4 * q, 0.0, 51.0);
  if (c == VideoCodec::H264) return std::clamp(51.0 - 0.4 * q, 0.0, 51.0);
  return std::clamp(60.0 - 0.5 * q, 0.0, 63.0);
}

// x264's chroma QP below luma's. The picture is seen, and measured, in RGB: with 4:2:0 one chroma
// sample's error reaches four pixels, with about the weight (R, G and B together) that one luma
// sample's error has in one pixel. Equal weight per unit of error asks for half the quantizer
// step on chroma, which is 6 QP (x264's default, with psy off, is 0).
constexpr const char* kX264ChromaOffset = "-6";

void set(AVCodecContext* ctx, const char* key, const std::string& value) {
  av_opt_set(ctx->priv_data, key, value.c_str(), 0);  // an option this build lacks is left out
}

// Latency first: no B-frames, no lookahead, one packet per frame; the CRF holds the quality
// where the budget allows, the VBV caps every frame at about two frames' share of the bit rate.
void configure(AVCodecContext* ctx, const char* name, const VideoSettings& s) {
  const std::string n = name;
  ctx->max_b_frames = 0;
  ctx->gop_size = s.fps * 10;  // a key frame every 10 s at least; more on request
  ctx->rc_max_rate = int64_t(s.kbps) * 1000;
  ctx->rc_buffer_size = int(std::min<int64_t>(INT32_MAX, ctx->rc_max_rate * 2 / s.fps));
  const std::string crf = std::to_string(int(std::lround(crf_for(n, s.codec, s.quality))));
  if (n == "libx264") {
    char x264_crf[16];  // x264 takes a fractional CRF
    std::snprintf(x264_crf, sizeof x264_crf, "%.1f", crf_for(n, s.codec, s.quality));
    set(ctx, "preset", "superfast");
    set(ctx, "tune", "zerolatency,psnr");
    set(ctx, "crf", x264_crf);
    set(ctx, "chromaoffset", kX264ChromaOffset);
    set(ctx, "forced-idr", "1");
  } else if (n == "libvpx-vp9") {
    ctx->bit_rate = ctx->rc_max_rate;  // constrained quality: the CRF under this ceiling
    set(ctx, "deadline", "realtime");
    set(ctx, "cpu-used", "8");
    set(ctx, "lag-in-frames", "0");
    set(ctx, "row-mt", "1");
    set(ctx, "crf", crf);
  } else if (n == "libaom-av1") {
    ctx->bit_rate = ctx->rc_max_rate;
    set(ctx, "usage", "realtime");
    set(ctx, "cpu-used", "8");
    set(ctx, "lag-in-frames", "0");
    set(ctx, "crf", crf);
  } else {  // the NVIDIA encoders
    set(ctx, "preset", "p1");
    set(ctx, "tune", "ull");
    set(ctx, "zerolatency", "1");
    set(ctx, "delay", "0");
    set(ctx, "rc", "vbr");
    set(ctx, "cq", crf);
    set(ctx, "forced-idr", "1");
  }
}

// `options` ("key=value;key=value") set on the encoder after configure(): its private options
// only (x264's preset, crf, x264-params; libvpx's cpu-used, ...), never the generic ones
// (pixel_format, bf, video_size) that the frames handed to it depend on. False (and why) when a
// pair is malformed or the encoder has no such option or refuses its value.
bool apply_options(AVCodecContext* ctx, const char* name, const std::string& options, std::string& why) {
  const auto trim = [](std::string t) {
    const size_t a = t.find_first_not_of(" \t"), b = t.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : t.substr(a, b - a + 1);
  };
  size_t p = 0;
  while (p < options.size()) {
    const size_t end = std::min(options.find(';', p), options.size());
    const std::string kv = trim(options.substr(p, end - p));
    p = end + 1;
    if (kv.empty()) continue;
    const size_t eq = kv.find('=');
    const std::string key = eq == std::string::npos ? std::string() : trim(kv.substr(0, eq));
    if (key.empty()) {
      why += std::string(name) + ": encoder option '" + kv + "' is not key=value; ";
      return false;
    }
    const std::string value = trim(kv.substr(eq + 1));
    const int err = av_opt_set(ctx->priv_data, key.c_str(), value.c_str(), 0);
    if (err < 0) {
      why += std::string(name) + ": encoder option " + key + "=" + value + ": " + av_error(err) + "; ";
      return false;
    }
  }
  return true;
}

ContextPtr open_encoder(const char* name, const VideoSettings& s, std::string& why) {
  const AVCodec* codec = avcodec_find_encoder_by_name(name);
  if (!codec) {
    why += std::string(name) + ": not in this libavcodec; ";
    return nullptr;
  }
  ContextPtr ctx(avcodec_alloc_context3(codec));
  ctx->width = s.width;
  ctx->height = s.height;
  ctx->pix_fmt = AV_PIX_FMT_YUV420P;
  ctx->time_base = AVRational{1, s.fps};
  ctx->framerate = AVRational{s.fps, 1};
  ctx->thread_count = s.threads;
  ctx->color_range = AVCOL_RANGE_MPEG;
  ctx->colorspace = AVCOL_SPC_BT709;
  ctx->color_primaries = AVCOL_PRI_BT709;
  ctx->color_trc = AVCOL_TRC_BT709;
  configure(ctx.get(), name, s);
  if (!apply_options(ctx.get(), name, s.encoder_options, why)) return nullptr;
  const int err = avcodec_open2(ctx.get(), codec, nullptr);
  if (err < 0) {  // a value the encoder reads only when it opens (x264's preset) fails here
    why += std::string(name) + ": " + av_error(err) +
           (s.encoder_options.empty() ? "" : " with encoder options '" + s.encoder_options + "'") + "; ";
    return nullptr;
  }
  return ctx;
}

void quiet_logs() {
  static std::once_flag once;
  // Failures come back as exceptions that name the encoder; a probe of an absent NVIDIA driver
  // on every session is noise in the server's log.
  std::call_once(once, [] { av_log_set_level(AV_LOG_FATAL); });
}

}  // namespace

std::optional<VideoCodec> video_codec_from_name(std::string_view name) {
  if (name == "h264") return VideoCodec::H264;
  if (name == "vp9") return VideoCodec::VP9;
  if (name == "av1") return VideoCodec::AV1;
  return std::nullopt;
}

const char* to_string(VideoCodec c) {
  switch (c) {
    case VideoCodec::H264: return "h264";
    case VideoCodec::VP9: return "vp9";
    case VideoCodec::AV1: return "av1";
  }
  return "?";
}

const std::vector<std::string>& available_codecs() {
  static const std::vector<std::string> codecs = [] {
    quiet_logs();
    std::vector<std::string> out{"jpeg"};
    for (VideoCodec c : {VideoCodec::H264, VideoCodec::VP9, VideoCodec::AV1}) {
      VideoSettings s;
      s.codec = c;
      s.width = s.height = 64;
      s.threads = 1;
      std::string why;
      for (const char* name : encoder_names(c))
        if (open_encoder(name, s, why)) {
          out.push_back(to_string(c));
          break;
        }
    }
    return out;
  }();
  return codecs;
}

bool codec_available(std::string_view name) {
  const auto& all = available_codecs();
  return std::find(all.begin(), all.end(), name) != all.end();
}

struct VideoEncoder::Impl {
  VideoSettings settings;
  const char* name = nullptr;
  ContextPtr ctx;
  FramePtr frame;
  PacketPtr packet;
  SwsPtr sws;
  int sws_w = 0, sws_h = 0;
  std::vector<uint8_t> padded;  // a frame of another size, with swscale's read padding
  int64_t pts = 0;
  static void scale_into_frame_impl(Impl& m, const uint8_t* rgb, int width, int height);
};

VideoEncoder::VideoEncoder(const VideoSettings& s) : impl_(std::make_unique<Impl>()) {
  quiet_logs();
  if (s.width <= 0 || s.height <= 0 || s.width % 2 || s.height % 2)
    throw std::runtime_error("video: the coded size must be positive and even, not " + std::to_string(s.width) + "x" +
                             std::to_string(s.height));
  if (s.kbps <= 0 || s.fps <= 0) throw std::runtime_error("video: kbps and fps must be positive");
  impl_->settings = s;
  std::string why;
  for (const char* name : encoder_names(s.codec))
    if ((impl_->ctx = open_encoder(name, s, why))) {
      impl_->name = name;
      break;
    }
  if (!impl_->ctx)
    throw std::runtime_error(std::string("video: no ") + to_string(s.codec) + " encoder opened (" + why + ")");
  impl_->frame.reset(av_frame_alloc());
  impl_->frame->format = AV_PIX_FMT_YUV420P;
  impl_->frame->width = s.width;
  impl_->frame->height = s.height;
  impl_->frame->color_range = AVCOL_RANGE_MPEG;
  impl_->frame->colorspace = AVCOL_SPC_BT709;
  if (av_frame_get_buffer(impl_->frame.get(), 0) < 0) throw std::runtime_error("video: out of memory");
  impl_->packet.reset(av_packet_alloc());
}

VideoEncoder::~VideoEncoder() = default;

const VideoSettings& VideoEncoder::settings() const { return impl_->settings; }
const char* VideoEncoder::encoder_name() const { return impl_->name; }

// A frame of another size (rendered smaller by the frame budget): scaled by swscale.
void VideoEncoder::Impl::scale_into_frame_impl(Impl& m, const uint8_t* rgb, int width, int height) {
  if (!m.sws || m.sws_w != width || m.sws_h != height) {
    // RGB (full range) to BT.709 limited-range 4:2:0, scaled to the coded size where it differs.
    m.sws.reset(sws_getContext(width, height, AV_PIX_FMT_RGB24, m.settings.width, m.settings.height, AV_PIX_FMT_YUV420P,
                               SWS_BILINEAR, nullptr, nullptr, nullptr));
    if (!m.sws)
      throw std::runtime_error("video: no scaler for " + std::to_string(width) + "x" + std::to_string(height));
    const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
    sws_setColorspaceDetails(m.sws.get(), bt709, 1, bt709, 0, 0, 1 << 16, 1 << 16);
    m.sws_w = width;
    m.sws_h = height;
  }
  // swscale's readers load past the last pixel (a SEGV under TSan, whose heap ends the caller's
  // tight buffer at a page): the frame is handed over from a copy with FFmpeg's input padding.
  const size_t bytes = size_t(width) * 3 * size_t(height);
  m.padded.resize(bytes + AV_INPUT_BUFFER_PADDING_SIZE);
  std::memcpy(m.padded.data(), rgb, bytes);
  std::memset(m.padded.data() + bytes, 0, AV_INPUT_BUFFER_PADDING_SIZE);
  const uint8_t* src[1] = {m.padded.data()};
  const int stride[1] = {width * 3};
  sws_scale(m.sws.get(), src, stride, 0, height, m.frame->data, m.frame->linesize);
}

VideoPacket VideoEncoder::encode(const uint8_t* rgb, int width, int height, bool force_key) {
  Impl& m = *impl_;
  if (av_frame_make_writable(m.frame.get()) < 0) throw std::runtime_error("video: frame not writable");
  if (width == m.settings.width && height == m.settings.height) {
    AVFrame* f = m.frame.get();
    rgb_to_yuv420_bt709(rgb, width, height,
                        {f->data[0], f->data[1], f->data[2], f->linesize[0], f->linesize[1], f->linesize[2]});
  } else {
    Impl::scale_into_frame_impl(m, rgb, width, height);
  }
  m.frame->pts = m.pts++;
  m.frame->pict_type = force_key ? AV_PICTURE_TYPE_I : AV_PICTURE_TYPE_NONE;
  m.frame->key_frame = force_key ? 1 : 0;
  int err = avcodec_send_frame(m.ctx.get(), m.frame.get());
  if (err < 0) throw std::runtime_error(std::string("video: ") + m.name + " refused a frame: " + av_error(err));
  VideoPacket out;
  for (;;) {
    err = avcodec_receive_packet(m.ctx.get(), m.packet.get());
    if (err == AVERROR(EAGAIN)) break;
    if (err < 0) throw std::runtime_error(std::string("video: ") + m.name + ": " + av_error(err));
    out.bytes.insert(out.bytes.end(), m.packet->data, m.packet->data + m.packet->size);
    out.key = out.key || (m.packet->flags & AV_PKT_FLAG_KEY);
    av_packet_unref(m.packet.get());
  }
  if (out.bytes.empty()) throw std::runtime_error(std::string("video: ") + m.name + " held a frame back");
  return out;
}

struct VideoDecoder::Impl {
  ContextPtr ctx;
  FramePtr frame;
  PacketPtr packet;
  SwsPtr sws;
};

VideoDecoder::VideoDecoder(VideoCodec c) : impl_(std::make_unique<Impl>()) {
  quiet_logs();
  // libavcodec 5's own AV1 decoder needs a hardware device; dav1d decodes in software.
  const AVCodec* codec = c == VideoCodec::H264  ? avcodec_find_decoder(AV_CODEC_ID_H264)
                         : c == VideoCodec::VP9 ? avcodec_find_decoder(AV_CODEC_ID_VP9)
                                                : avcodec_find_decoder_by_name("libdav1d");
  if (!codec) throw std::runtime_error(std::string("video: no ") + to_string(c) + " decoder");
  impl_->ctx.reset(avcodec_alloc_context3(codec));
  impl_->ctx->thread_count = 1;  // frame threads would hold pictures back
  impl_->ctx->flags |= AV_CODEC_FLAG_LOW_DELAY;
  av_opt_set(impl_->ctx->priv_data, "max_frame_delay", "1", 0);
  const int err = avcodec_open2(impl_->ctx.get(), codec, nullptr);
  if (err < 0) throw std::runtime_error(std::string("video: ") + codec->name + ": " + av_error(err));
  impl_->frame.reset(av_frame_alloc());
  impl_->packet.reset(av_packet_alloc());
}

VideoDecoder::~VideoDecoder() = default;

bool VideoDecoder::decode(const std::vector<uint8_t>& bytes, std::vector<uint8_t>& rgb, int& width, int& height) {
  Impl& m = *impl_;
  if (av_new_packet(m.packet.get(), int(bytes.size())) < 0) return false;
  std::copy(bytes.begin(), bytes.end(), m.packet->data);
  const int sent = avcodec_send_packet(m.ctx.get(), m.packet.get());
  av_packet_unref(m.packet.get());
  if (sent < 0) return false;
  bool got = false;
  while (avcodec_receive_frame(m.ctx.get(), m.frame.get()) == 0) {
    AVFrame* f = m.frame.get();
    width = f->width;
    height = f->height;
    m.sws.reset(sws_getContext(f->width, f->height, AVPixelFormat(f->format), f->width, f->height, AV_PIX_FMT_RGB24,
                               SWS_BILINEAR, nullptr, nullptr, nullptr));
    const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
    sws_setColorspaceDetails(m.sws.get(), bt709, f->color_range == AVCOL_RANGE_JPEG, bt709, 1, 0, 1 << 16, 1 << 16);
    rgb.assign(size_t(width) * height * 3, 0);
    uint8_t* dst[1] = {rgb.data()};
    const int stride[1] = {width * 3};
    sws_scale(m.sws.get(), f->data, f->linesize, 0, f->height, dst, stride);
    av_frame_unref(f);
    got = true;
  }
  return got;
}

}  // namespace peakcast::encode
