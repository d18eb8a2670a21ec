#include "session/video_channel.h"

#include <algorithm>
#include <cmath>

namespace peakcast {

uint64_t VideoChannel::take_ticket() { return next_ticket_++; }

void VideoChannel::request_key_frame() { key_wanted_ = true; }

int VideoChannel::encoders_opened() const { return opened_; }

namespace {
bool same(const encode::VideoSettings& a, const encode::VideoSettings& b) {
  return a.codec == b.codec && a.width == b.width && a.height == b.height && a.kbps == b.kbps &&
         a.quality == b.quality && a.fps == b.fps && a.threads == b.threads;
}
}  // namespace

std::optional<VideoFrameOut> VideoChannel::encode(uint64_t ticket, const encode::VideoSettings& settings,
                                                  const uint8_t* rgb, int width, int height, std::string& error) {
  std::optional<VideoFrameOut> result;
  encode(ticket, settings, rgb, width, height, [&](std::optional<VideoFrameOut> out, const std::string& e) {
    result = std::move(out);
    error = e;
  });
  return result;
}

void VideoChannel::encode(uint64_t ticket, const encode::VideoSettings& settings, const uint8_t* rgb, int width,
                          int height, const Then& then) {
  std::unique_lock lock(m_);
  turn_.wait(lock, [&] { return serving_ == ticket; });
  struct Next {  // the next ticket's turn, whatever happens here
    VideoChannel& c;
    ~Next() {
      c.serving_++;
      c.turn_.notify_all();
    }
  } next{*this};
  std::optional<VideoFrameOut> result;
  std::string error;
  try {
    if (!encoder_ || !same(current_, settings)) {
      encoder_.reset();
      encoder_ = std::make_unique<encode::VideoEncoder>(settings);
      current_ = settings;
      opened_++;
      key_wanted_ = false;  // a new encoder starts with one
    }
    const bool force = key_wanted_.exchange(false);
    VideoFrameOut out;
    out.packet = encoder_->encode(rgb, width, height, force);
    out.width = settings.width;
    out.height = settings.height;
    out.encoder = encoder_->encoder_name();
    const auto now = std::chrono::steady_clock::now();
    sent_.emplace_back(now, out.packet.bytes.size());
    while (!sent_.empty() && now - sent_.front().first > std::chrono::seconds(1)) sent_.pop_front();
    size_t bytes = 0;
    for (const auto& s : sent_) bytes += s.second;
    out.kbps = double(bytes) * 8.0 / 1000.0;
    result = std::move(out);
  } catch (const std::exception& e) {
    error = e.what();
    encoder_.reset();  // the next frame starts a new encoder, with a key frame
  }
  then(std::move(result), error);  // still this ticket's turn
}

std::pair<int, int> video_coded_size(int width, int height, double interactive_scale) {
  auto side = [&](int v) { return std::max(16, int(std::lround(v * interactive_scale / 2.0)) * 2); };
  return {side(width), side(height)};
}

}  // namespace peakcast
