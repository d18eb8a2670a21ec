// A movie file written as its frames come (POST /api/movie): H.264 in fragmented MP4 or VP9 in
// WebM through Debian's libavformat and libavcodec (PEAKCAST_HAVE_VIDEO builds), a ZIP of PNGs,
// or the frames' RGB bytes one after the other (what a script puts in arrays).
// Each call hands back the bytes the file has gained, so the file streams while it is made: no
// seek back, no temporary file.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace peakcast::encode {

enum class MovieFormat { Mp4, Webm, PngZip, Rgb };

std::optional<MovieFormat> movie_format_from_name(std::string_view name);  // "mp4", "webm", "png-zip", "rgb"
const char* to_string(MovieFormat f);
const char* content_type(MovieFormat f);    // video/mp4, video/webm, application/zip, application/octet-stream
const char* file_extension(MovieFormat f);  // mp4, webm, zip, rgb
// Whether this build writes the format (mp4 and webm need libavformat).
bool movie_format_available(MovieFormat f);

struct MovieSettings {
  MovieFormat format = MovieFormat::Mp4;
  int width = 0, height = 0;  // every frame's; mp4 and webm want both even (4:2:0)
  int fps = 30;
  int quality = 90;  // 10..100 onto the codec's CRF (video.cpp's mapping); PNG is lossless
  int threads = 1;
};

class MovieWriter {
 public:
  virtual ~MovieWriter() = default;
  // rgb: width * height * 3 bytes, row 0 at the top. Returns what the file gained (may be empty:
  // a fragment is written about once a second).
  virtual std::string add(const uint8_t* rgb) = 0;
  // The file's rest: pending frames, the index, the end.
  virtual std::string finish() = 0;
  virtual const char* encoder_name() const = 0;
};

// Throws std::runtime_error (the format not in this build, sizes it cannot take, the encoder).
std::unique_ptr<MovieWriter> open_movie_writer(const MovieSettings& settings);

// The ZIP of PNGs and the raw frames (encode/movie_writer.cpp): open_movie_writer's for
// MovieFormat::PngZip and MovieFormat::Rgb.
std::unique_ptr<MovieWriter> open_image_movie_writer(const MovieSettings& settings);
// The video containers (encode/movie_video.cpp, or a refusal without libavformat).
std::unique_ptr<MovieWriter> open_video_movie_writer(const MovieSettings& settings);

}  // namespace peakcast::encode
