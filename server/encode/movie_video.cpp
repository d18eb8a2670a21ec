// H.264 in fragmented MP4 and VP9 in WebM, muxed by libavformat into memory as the frames come
// (encode/movie_writer.h). MP4 must be fragmented to stream (a plain MP4's index is written at
// the end and points back into the file): an empty `moov` first, then one `moof` + `mdat` per
// second; browsers, ffmpeg, VLC and QuickTime play it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "encode/movie_writer.h"
#include "encode/yuv420.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
}

namespace peakcast::encode {
namespace {

std::string av_error(int err) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(err, buf, sizeof buf);
  return buf;
}

class VideoMovieWriter final : public MovieWriter {
 public:
  explicit VideoMovieWriter(const MovieSettings& s) : s_(s) {
    if (s.width % 2 || s.height % 2)
      throw std::runtime_error("movie: an " + std::string(to_string(s.format)) +
                               " movie needs an even width and height (4:2:0 video), not " + std::to_string(s.width) +
                               "x" + std::to_string(s.height));
    av_log_set_level(AV_LOG_FATAL);
    open_encoder();
    open_muxer();
  }

  ~VideoMovieWriter() override {
    if (fmt_) {
      if (fmt_->pb) {
        av_freep(&fmt_->pb->buffer);
        avio_context_free(&fmt_->pb);
      }
      avformat_free_context(fmt_);
    }
    av_frame_free(&frame_);
    av_packet_free(&packet_);
    avcodec_free_context(&ctx_);
  }

  std::string add(const uint8_t* rgb) override {
    if (av_frame_make_writable(frame_) < 0) throw std::runtime_error("movie: frame not writable");
    rgb_to_yuv420_bt709(rgb, s_.width, s_.height,
                        {frame_->data[0], frame_->data[1], frame_->data[2], frame_->linesize[0], frame_->linesize[1],
                         frame_->linesize[2]});
    frame_->pts = pts_++;
    send(frame_);
    avio_flush(fmt_->pb);  // what the muxer wrote leaves its buffer now
    return take();
  }

  std::string finish() override {
    send(nullptr);  // drain the encoder
    const int err = av_write_trailer(fmt_);
    if (err < 0) throw std::runtime_error(std::string("movie: ") + av_error(err));
    avio_flush(fmt_->pb);
    return take();
  }

  const char* encoder_name() const override { return codec_name_; }

 private:
  void open_encoder() {
    codec_name_ = s_.format == MovieFormat::Mp4 ? "libx264" : "libvpx-vp9";
    const AVCodec* codec = avcodec_find_encoder_by_name(codec_name_);
    if (!codec) throw std::runtime_error(std::string("movie: this libavcodec has no ") + codec_name_);
    ctx_ = avcodec_alloc_context3(codec);
    ctx_->width = s_.width;
    ctx_->height = s_.height;
    ctx_->pix_fmt = AV_PIX_FMT_YUV420P;
    ctx_->time_base = AVRational{1, s_.fps};
    ctx_->framerate = AVRational{s_.fps, 1};
    ctx_->gop_size = s_.fps;  // a key frame a second: a fragment a second, and seeking
    ctx_->thread_count = s_.threads;
    ctx_->color_range = AVCOL_RANGE_MPEG;
    ctx_->colorspace = AVCOL_SPC_BT709;
    ctx_->color_primaries = AVCOL_PRI_BT709;
    ctx_->color_trc = AVCOL_TRC_BT709;
    ctx_->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;  // both containers keep the codec's headers in their own
    const double q = std::clamp(s_.quality, 10, 100);
    char crf[16];
    if (s_.format == MovieFormat::Mp4) {  // the mapping of encode/video.cpp (libx264: CRF 17.5 at 90)
      std::snprintf(crf, sizeof crf, "%.1f", std::clamp(53.5 - 0.4 * q, 0.0, 51.0));
      av_opt_set(ctx_->priv_data, "preset", "veryfast", 0);
      av_opt_set(ctx_->priv_data, "crf", crf, 0);
    } else {  // constant quality (no bit-rate target): CRF 15 at 90
      std::snprintf(crf, sizeof crf, "%d", int(std::lround(std::clamp(60.0 - 0.5 * q, 0.0, 63.0))));
      ctx_->bit_rate = 0;
      av_opt_set(ctx_->priv_data, "crf", crf, 0);
      av_opt_set(ctx_->priv_data, "deadline", "realtime", 0);
      av_opt_set(ctx_->priv_data, "cpu-used", "6", 0);
      av_opt_set(ctx_->priv_data, "row-mt", "1", 0);
    }
    if (const int err = avcodec_open2(ctx_, codec, nullptr); err < 0)
      throw std::runtime_error(std::string("movie: ") + codec_name_ + ": " + av_error(err));
    frame_ = av_frame_alloc();
    frame_->format = AV_PIX_FMT_YUV420P;
    frame_->width = s_.width;
    frame_->height = s_.height;
    frame_->color_range = AVCOL_RANGE_MPEG;
    frame_->colorspace = AVCOL_SPC_BT709;
    if (av_frame_get_buffer(frame_, 0) < 0) throw std::runtime_error("movie: out of memory");
    packet_ = av_packet_alloc();
  }

  // libavformat writes into `out_` through this (never seeks: the output is a stream).
  static int write_bytes(void* opaque, uint8_t* data, int size) {
    static_cast<VideoMovieWriter*>(opaque)->out_.append(reinterpret_cast<const char*>(data), size_t(size));
    return size;
  }

  void open_muxer() {
    const char* container = s_.format == MovieFormat::Mp4 ? "mp4" : "webm";
    if (avformat_alloc_output_context2(&fmt_, nullptr, container, nullptr) < 0 || !fmt_)
      throw std::runtime_error(std::string("movie: this libavformat has no ") + container + " muxer");
    constexpr int kBuffer = 64 * 1024;
    auto* buffer = static_cast<uint8_t*>(av_malloc(kBuffer));
    fmt_->pb = avio_alloc_context(buffer, kBuffer, 1, this, nullptr, &VideoMovieWriter::write_bytes, nullptr);
    fmt_->pb->seekable = 0;
    fmt_->flags |= AVFMT_FLAG_CUSTOM_IO;
    stream_ = avformat_new_stream(fmt_, nullptr);
    avcodec_parameters_from_context(stream_->codecpar, ctx_);
    stream_->time_base = ctx_->time_base;
    stream_->avg_frame_rate = ctx_->framerate;
    AVDictionary* options = nullptr;
    if (s_.format == MovieFormat::Mp4) {
      av_dict_set(&options, "movflags", "empty_moov+default_base_moof+frag_keyframe", 0);
    } else {
      av_dict_set(&options, "live", "1", 0);  // no cues to seek back for
    }
    const int err = avformat_write_header(fmt_, &options);
    av_dict_free(&options);
    if (err < 0) throw std::runtime_error(std::string("movie: ") + container + " header: " + av_error(err));
  }

  // One frame in (null: the end), every packet out into the muxer.
  void send(AVFrame* frame) {
    int err = avcodec_send_frame(ctx_, frame);
    if (err < 0) throw std::runtime_error(std::string("movie: ") + codec_name_ + " refused a frame: " + av_error(err));
    for (;;) {
      err = avcodec_receive_packet(ctx_, packet_);
      if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) break;
      if (err < 0) throw std::runtime_error(std::string("movie: ") + codec_name_ + ": " + av_error(err));
      av_packet_rescale_ts(packet_, ctx_->time_base, stream_->time_base);
      packet_->stream_index = stream_->index;
      err = av_interleaved_write_frame(fmt_, packet_);  // takes the packet's reference
      if (err < 0) throw std::runtime_error(std::string("movie: muxing: ") + av_error(err));
    }
  }

  std::string take() {
    std::string bytes;
    bytes.swap(out_);
    return bytes;
  }

  MovieSettings s_;
  const char* codec_name_ = "";
  AVCodecContext* ctx_ = nullptr;
  AVFrame* frame_ = nullptr;
  AVPacket* packet_ = nullptr;
  AVFormatContext* fmt_ = nullptr;
  AVStream* stream_ = nullptr;
  int64_t pts_ = 0;
  std::string out_;
};

}  // namespace

bool movie_format_available(MovieFormat f) {
  if (f == MovieFormat::PngZip || f == MovieFormat::Rgb) return true;
  const char* name = f == MovieFormat::Mp4 ? "libx264" : "libvpx-vp9";
  return avcodec_find_encoder_by_name(name) &&
         av_guess_format(f == MovieFormat::Mp4 ? "mp4" : "webm", nullptr, nullptr);
}

std::unique_ptr<MovieWriter> open_video_movie_writer(const MovieSettings& s) {
  return std::make_unique<VideoMovieWriter>(s);
}

}  // namespace peakcast::encode
