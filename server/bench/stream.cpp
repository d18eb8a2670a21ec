// `bench stream`: an orbit rendered and encoded as the server streams it (docs/streaming.md):
// the bit rate, the encode ms per frame and the PSNR of the decoded frames (libavcodec's decoder,
// or TurboJPEG for jpeg) against the lossless renders. One frame at a time, in order, as a
// session's stream is encoded; the renders come first and the decoding after, so the encoder has
// the cores to itself.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "encode/jpeg.h"
#include "encode/video.h"

namespace peakcast::bench {
namespace {

using Clock = std::chrono::steady_clock;

struct StreamArgs {
  std::string volume;
  std::string codec = "h264";
  std::string size = "1024x1024";
  double fps = 30, seconds = 4, orbit_deg_per_s = 30;
  int kbps = 8000, quality = 70, passes = 1;
  std::string encoder_options;
  bool json = false;
};

double psnr(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double se = 0;
  for (size_t i = 0; i < a.size(); ++i) se += double(int(a[i]) - int(b[i])) * (int(a[i]) - int(b[i]));
  const double mse = se / double(a.size());
  return mse == 0 ? 99.0 : 10 * std::log10(255.0 * 255.0 / mse);
}

// The lossless renders of the orbit, one 8-bit RGB frame per planned frame; their wall time goes into `render_s`.
std::vector<std::vector<uint8_t>> render_orbit(const StreamArgs& a, render::Renderer& renderer,
                                               const render::ResidentVolume& resident, const Volume& vol, int w, int h,
                                               int frames, double& render_s) {
  ResolvedScene s = bench_scene(vol, w, "trilinear");
  s.scene.width = w;
  s.scene.height = h;
  const Camera start = s.camera;
  std::vector<std::vector<uint8_t>> renders;
  render::RenderRequest req;
  req.output = render::RenderOutput::Rgb8;
  const auto t_render = Clock::now();
  for (int f = 0; f < frames; ++f) {
    s.camera = orbit_camera(start, a.orbit_deg_per_s * f / a.fps);
    renders.push_back(renderer.render(resident, s, req, nullptr).rgb8.rgb);
  }
  render_s = std::chrono::duration<double>(Clock::now() - t_render).count();
  return renders;
}

// What encoding the orbit measured: every frame's encode ms over all passes, and the first pass's packets.
struct Encoded {
  std::vector<double> encode_ms;
  std::string encoder = "turbojpeg";
  std::vector<std::vector<uint8_t>> packets;
};

// Encodes the orbit --passes times, each pass with a fresh encoder (JPEG when `video` is empty).
Encoded encode_orbit(const StreamArgs& a, const std::optional<encode::VideoCodec>& video,
                     const std::vector<std::vector<uint8_t>>& renders, int w, int h) {
  Encoded e;
  encode::JpegEncoder jpeg;
  for (int pass = 0; pass < a.passes; ++pass) {
    std::unique_ptr<encode::VideoEncoder> enc;
    if (video) {
      encode::VideoSettings vs;
      vs.codec = *video;
      vs.width = w;
      vs.height = h;
      vs.kbps = a.kbps;
      vs.quality = a.quality;
      vs.fps = int(std::lround(a.fps));
      vs.encoder_options = a.encoder_options;
      enc = std::make_unique<encode::VideoEncoder>(vs);
      e.encoder = enc->encoder_name();
    }
    for (const auto& rgb : renders) {
      const auto t0 = Clock::now();
      std::vector<uint8_t> packet = enc ? enc->encode(rgb.data(), w, h, false).bytes
                                        : jpeg.encode(rgb.data(), w, h, a.quality, encode::Subsampling::S420);
      e.encode_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      if (pass == 0) e.packets.push_back(std::move(packet));
    }
  }
  return e;
}

// Decodes the first pass's packets in order: each frame's PSNR against its render, into `db`; returns their bytes.
size_t decode_orbit(const std::optional<encode::VideoCodec>& video, const Encoded& e,
                    const std::vector<std::vector<uint8_t>>& renders, std::vector<double>& db) {
  const std::vector<std::vector<uint8_t>>& packets = e.packets;
  size_t bytes = 0;
  std::unique_ptr<encode::VideoDecoder> dec;
  if (video) dec = std::make_unique<encode::VideoDecoder>(*video);
  for (size_t f = 0; f < packets.size(); ++f) {
    std::vector<uint8_t> out;
    int dw = 0, dh = 0;
    if (dec) {
      if (!dec->decode(packets[f], out, dw, dh)) throw std::runtime_error("the decoder gave no picture for a frame");
    } else {
      out = encode::decode_jpeg(packets[f].data(), packets[f].size(), dw, dh);
    }
    bytes += packets[f].size();
    db.push_back(psnr(renders[f], out));
  }
  return bytes;
}

// What the report shows beside the arguments and the encoding.
struct StreamResult {
  int w = 0, h = 0, frames = 0;
  bool video = false;
  double render_s = 0, mbps = 0, mean_db = 0;
  std::vector<double> db;
};

// Prints the report: one JSON object (--json) or two lines of text.
void print_stream(const StreamArgs& a, const Encoded& e, const StreamResult& r) {
  const std::vector<double>& db = r.db;
  const std::vector<double>& encode_ms = e.encode_ms;
  const std::string& encoder = e.encoder;
  if (a.json) {
    nlohmann::json j = {{"codec", a.codec},
                        {"encoder", encoder},
                        {"mbps", r.mbps},
                        {"psnr_db", r.mean_db},
                        {"psnr_db_min", *std::min_element(db.begin(), db.end())},
                        {"encode_ms", median(encode_ms)},
                        {"encode_ms_max", *std::max_element(encode_ms.begin(), encode_ms.end())},
                        {"fps", a.fps},
                        {"frames", r.frames},
                        {"width", r.w},
                        {"height", r.h},
                        {"kbps", r.video ? a.kbps : 0},
                        {"quality", a.quality},
                        {"delay_frames", 0},
                        {"encoder_options", a.encoder_options},
                        {"passes", a.passes}};
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s (%s) %dx%d, %d frames at %.0f frames/s over a %.0f-degree orbit (rendered in %.1f s)\n",
                a.codec.c_str(), encoder.c_str(), r.w, r.h, r.frames, a.fps, a.orbit_deg_per_s * r.frames / a.fps,
                r.render_s);
    std::printf(
        "  %.2f Mbit/s, PSNR %.2f dB (min %.2f), encode %.2f ms per frame (median; max %.2f; %d pass%s), delay 0 "
        "frames\n",
        r.mbps, r.mean_db, *std::min_element(db.begin(), db.end()), median(encode_ms),
        *std::max_element(encode_ms.begin(), encode_ms.end()), a.passes, a.passes == 1 ? "" : "es");
  }
}

int run_stream(const StreamArgs& a) {
  int w = 0, h = 0;
  if (std::sscanf(a.size.c_str(), "%dx%d", &w, &h) != 2 || w < 16 || h < 16 || w % 2 || h % 2)
    throw std::invalid_argument("--size: WxH, even, at least 16x16 (got '" + a.size + "')");
  const auto video = encode::video_codec_from_name(a.codec);
  if (a.codec != "jpeg" && !video)
    throw std::invalid_argument("--codec: jpeg, h264, vp9 or av1 (got '" + a.codec + "')");
  if (video && !encode::codec_available(a.codec))
    throw std::invalid_argument("--codec " + a.codec + ": this build cannot encode it");
  const int frames = std::max(1, int(std::lround(a.fps * a.seconds)));

  // The lossless renders of the orbit: what the decoded frames are measured against.
  BenchRenderer b = make_bench_renderer();
  auto vol = bench_volume(a.volume);
  auto resident = b.renderer->make_resident(vol);
  StreamResult r;
  r.w = w, r.h = h, r.frames = frames, r.video = bool(video);
  const auto renders = render_orbit(a, *b.renderer, *resident, *vol, w, h, frames, r.render_s);

  // Each pass encodes the whole orbit with a fresh encoder, back to back as a stream is encoded
  // (the timed part); the first pass's packets are then decoded in order, for the bits and the
  // PSNR. The encode ms is the median (and the max) over every pass: one pass's median varied by
  // 20-40% between runs on a shared 2-core machine.
  const Encoded enc = encode_orbit(a, video, renders, w, h);
  const size_t bytes = decode_orbit(video, enc, renders, r.db);
  for (double d : r.db) r.mean_db += d / double(r.db.size());
  r.mbps = double(bytes) * 8.0 / (frames / a.fps) / 1e6;
  print_stream(a, enc, r);
  return 0;
}

}  // namespace

void add_stream_command(CLI::App& bench, Runner& run) {
  auto args = std::make_shared<StreamArgs>();
  auto* c = bench.add_subcommand("stream", "Bit rate, encode ms and PSNR of an orbit streamed as JPEG or video");
  c->add_option("volume", args->volume, "a volume file, or a generator kind (blobs, ml, ...)")->required();
  c->add_option("--codec", args->codec, "jpeg, h264, vp9 or av1");
  c->add_option("--size", args->size, "frame size WxH (even)");
  c->add_option("--fps", args->fps, "frames per second the stream is planned for")->check(CLI::Range(1.0, 240.0));
  c->add_option("--seconds", args->seconds, "length of the orbit")->check(CLI::Range(0.1, 600.0));
  c->add_option("--kbps", args->kbps, "video bit-rate ceiling (kbit/s)")->check(CLI::Range(100, 200000));
  c->add_option("--quality", args->quality, "JPEG quality, or the video CRF it maps onto (10..100)")
      ->check(CLI::Range(10, 100));
  c->add_option(
      "--encoder-options", args->encoder_options,
      "the video encoder's own options over peakcast's: \"key=value;key=value\" (preset, crf, x264-params, ...)");
  c->add_option("--passes", args->passes, "encode the orbit this many times; encode ms is the median over all")
      ->check(CLI::Range(1, 100));
  c->add_option("--orbit", args->orbit_deg_per_s, "degrees per second the camera turns");
  c->add_flag("--json", args->json, "one JSON object: codec, mbps, psnr_db, encode_ms, fps, ...");
  c->callback([args, &run] { run = [args] { return run_stream(*args); }; });
}

}  // namespace peakcast::bench
