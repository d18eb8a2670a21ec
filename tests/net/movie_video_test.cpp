// The movie files (server/encode/movie_writer.h, H.264 in fragmented MP4 and VP9 in WebM) read
// back by libavformat and libavcodec as a player would: every frame there, in order, within a
// measured PSNR of what went in, and bytes leaving while the movie is made.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "encode/movie_writer.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libswscale/swscale.h>
}

namespace peakcast::encode {

std::vector<uint8_t> picture(int w, int h, int t);  // video_test.cpp: a blob moving over a gradient

namespace {

struct Memory {
  const std::string* bytes;
  size_t at = 0;
};

int read_memory(void* opaque, uint8_t* buf, int size) {
  auto* m = static_cast<Memory*>(opaque);
  const size_t n = std::min(size_t(size), m->bytes->size() - m->at);
  if (n == 0) return AVERROR_EOF;
  std::memcpy(buf, m->bytes->data() + m->at, n);
  m->at += n;
  return int(n);
}

// Every picture of the file, as RGB, in presentation order (the demuxer's, with no seeking).
std::vector<std::vector<uint8_t>> decode_file(const std::string& file, int& w, int& h, std::string& container) {
  Memory mem{&file};
  AVFormatContext* fmt = avformat_alloc_context();
  auto* buffer = static_cast<uint8_t*>(av_malloc(4096));
  fmt->pb = avio_alloc_context(buffer, 4096, 0, &mem, &read_memory, nullptr, nullptr);
  fmt->pb->seekable = 0;
  std::vector<std::vector<uint8_t>> out;
  if (avformat_open_input(&fmt, nullptr, nullptr, nullptr) < 0) return out;
  avformat_find_stream_info(fmt, nullptr);
  container = fmt->iformat->name;
  const AVStream* st = fmt->streams[0];
  const AVCodec* codec = avcodec_find_decoder(st->codecpar->codec_id);
  AVCodecContext* ctx = avcodec_alloc_context3(codec);
  avcodec_parameters_to_context(ctx, st->codecpar);
  avcodec_open2(ctx, codec, nullptr);
  AVPacket* pkt = av_packet_alloc();
  AVFrame* frame = av_frame_alloc();
  SwsContext* sws = nullptr;
  auto drain = [&] {
    while (avcodec_receive_frame(ctx, frame) == 0) {
      w = frame->width;
      h = frame->height;
      sws = sws_getCachedContext(sws, w, h, AVPixelFormat(frame->format), w, h, AV_PIX_FMT_RGB24, SWS_BILINEAR, nullptr,
                                 nullptr, nullptr);
      const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
      sws_setColorspaceDetails(sws, bt709, 0, bt709, 1, 0, 1 << 16, 1 << 16);
      std::vector<uint8_t> rgb(size_t(w) * h * 3 + 64);
      uint8_t* dst[1] = {rgb.data()};
      const int stride[1] = {w * 3};
      sws_scale(sws, frame->data, frame->linesize, 0, h, dst, stride);
      rgb.resize(size_t(w) * h * 3);
      out.push_back(std::move(rgb));
    }
  };
  while (av_read_frame(fmt, pkt) >= 0) {
    avcodec_send_packet(ctx, pkt);
    av_packet_unref(pkt);
    drain();
  }
  avcodec_send_packet(ctx, nullptr);
  drain();
  sws_freeContext(sws);
  av_frame_free(&frame);
  av_packet_free(&pkt);
  avcodec_free_context(&ctx);
  av_freep(&fmt->pb->buffer);
  avio_context_free(&fmt->pb);
  avformat_close_input(&fmt);
  return out;
}

double psnr(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double se = 0;
  for (size_t i = 0; i < a.size(); ++i) se += double(a[i] - b[i]) * (a[i] - b[i]);
  return se == 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 * double(a.size()) / se);
}

struct Case {
  MovieFormat format;
  const char* container;  // libavformat's name of the demuxer that reads it
  double min_psnr;        // measured, see the test's comment
};

class MovieFiles : public ::testing::TestWithParam<Case> {};

// 75 frames at 25 fps, 160x96, quality 90. Measured here: the worst frame's PSNR 42.05 dB (mp4,
// libx264 CRF 17.5) and 41.92 dB (webm, libvpx-vp9 CRF 15); the bounds leave 3 dB. Decoding
// these BT.709 frames as BT.601 drops them to 35.8 and 35.6 dB, so a colour-space slip fails here.
TEST_P(MovieFiles, ReadBackAsAPlayerWouldEveryFrameInOrder) {
  const Case c = GetParam();
  if (!movie_format_available(c.format)) GTEST_SKIP() << "no " << to_string(c.format) << " in this libavcodec";
  const int w = 160, h = 96, n = 75, fps = 25;
  auto writer = open_movie_writer({c.format, w, h, fps, 90});
  std::string file;
  std::vector<size_t> size_after;
  std::vector<std::vector<uint8_t>> in;
  for (int i = 0; i < n; ++i) {
    in.push_back(picture(w, h, i % 40));
    file += writer->add(in.back().data());
    size_after.push_back(file.size());
  }
  const size_t before_finish = file.size();
  file += writer->finish();
  // It streams: the file has grown past its header by the second second, long before the end.
  EXPECT_GT(size_after[2 * fps + 1], size_after[0] + 1000) << "bytes leave as the movie is made";
  EXPECT_GT(before_finish, file.size() / 2);
  int dw = 0, dh = 0;
  std::string container;
  const auto out = decode_file(file, dw, dh, container);
  EXPECT_NE(container.find(c.container), std::string::npos) << container;
  ASSERT_EQ(out.size(), size_t(n));
  EXPECT_EQ(dw, w);
  EXPECT_EQ(dh, h);
  double worst = 99;
  for (int i = 0; i < n; ++i) worst = std::min(worst, psnr(in[size_t(i)], out[size_t(i)]));
  EXPECT_GT(worst, c.min_psnr);
  // Frames in order: each decoded frame is nearer its own input than its neighbour's.
  for (int i = 1; i < n; ++i) {
    if (i % 40 == 0) continue;  // the blob jumps back: frame i's neighbour is not its predecessor
    EXPECT_GT(psnr(in[size_t(i)], out[size_t(i)]), psnr(in[size_t(i) - 1], out[size_t(i)])) << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, MovieFiles,
                         ::testing::Values(Case{MovieFormat::Mp4, "mp4", 39.0}, Case{MovieFormat::Webm, "webm", 39.0}),
                         [](const auto& info) { return std::string(to_string(info.param.format)); });

TEST(MovieFiles, AVideoOfOddSizeIsRefusedByName) {
  try {
    open_movie_writer({MovieFormat::Mp4, 161, 96, 25, 90});
    FAIL() << "an odd width was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("even width and height"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace peakcast::encode
