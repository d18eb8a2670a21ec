// A build without libavcodec and libavformat (PEAKCAST_WITH_VIDEO found nothing): a movie is a
// ZIP of PNGs only.
#include <stdexcept>
#include <string>

#include "encode/movie_writer.h"

namespace peakcast::encode {

bool movie_format_available(MovieFormat f) { return f == MovieFormat::PngZip || f == MovieFormat::Rgb; }

std::unique_ptr<MovieWriter> open_video_movie_writer(const MovieSettings& s) {
  throw std::runtime_error(std::string("movie: this build has no libavcodec/libavformat, so no ") +
                           to_string(s.format) + " (formats png-zip and rgb work everywhere)");
}

}  // namespace peakcast::encode
