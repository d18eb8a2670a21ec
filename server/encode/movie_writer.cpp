#include "encode/movie_writer.h"

#include <cstdio>
#include <limits>
#include <stdexcept>
#include <vector>

#include <zlib.h>

#include "encode/png.h"

namespace peakcast::encode {

namespace {

// Each format's name, content type and file extension, in one place.
struct FormatNames {
  MovieFormat format;
  const char *name, *content_type, *extension;
};
constexpr FormatNames kFormats[] = {{MovieFormat::Mp4, "mp4", "video/mp4", "mp4"},
                                    {MovieFormat::Webm, "webm", "video/webm", "webm"},
                                    {MovieFormat::PngZip, "png-zip", "application/zip", "zip"},
                                    {MovieFormat::Rgb, "rgb", "application/octet-stream", "rgb"}};

const FormatNames& names_of(MovieFormat f) {
  for (const FormatNames& n : kFormats)
    if (n.format == f) return n;
  return kFormats[0];
}

}  // namespace

std::optional<MovieFormat> movie_format_from_name(std::string_view name) {
  for (const FormatNames& n : kFormats)
    if (name == n.name) return n.format;
  return std::nullopt;
}

const char* to_string(MovieFormat f) { return names_of(f).name; }
const char* content_type(MovieFormat f) { return names_of(f).content_type; }
const char* file_extension(MovieFormat f) { return names_of(f).extension; }

std::unique_ptr<MovieWriter> open_movie_writer(const MovieSettings& s) {
  if (s.width < 1 || s.height < 1 || s.fps < 1) throw std::runtime_error("movie: empty frames or no frame rate");
  const bool image = s.format == MovieFormat::PngZip || s.format == MovieFormat::Rgb;
  return image ? open_image_movie_writer(s) : open_video_movie_writer(s);
}

namespace {

// A ZIP of stored (uncompressed: PNG is compressed already) entries, frame_00000.png on, each
// written whole as its PNG is made: its CRC and sizes are known, so the local header carries them
// (no data descriptor) and the central directory follows the last. Plain ZIP (not ZIP64): the
// file stays under 4 GiB, which net/rest_movie.cpp checks before it starts.
class PngZipWriter final : public MovieWriter {
 public:
  explicit PngZipWriter(const MovieSettings& s) : s_(s) {}

  std::string add(const uint8_t* rgb) override {
    const std::vector<unsigned char> png = encode_png(rgb, s_.width, s_.height, 3);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", int(entries_.size()));
    const uint32_t crc = uint32_t(crc32(crc32(0L, Z_NULL, 0), png.data(), uInt(png.size())));
    if (offset_ + png.size() + 128 > std::numeric_limits<uint32_t>::max())
      throw std::runtime_error("movie: the ZIP passed 4 GiB (smaller frames, or fewer)");
    entries_.push_back({name, crc, uint32_t(png.size()), uint32_t(offset_)});
    std::string out;
    put32(out, 0x04034b50);
    entry_fields(out, entries_.back());
    put16(out, 0);  // extra field length
    out += name;
    out.append(reinterpret_cast<const char*>(png.data()), png.size());
    offset_ += out.size();
    return out;
  }

  std::string finish() override {
    std::string out;
    for (const Entry& e : entries_) {
      put32(out, 0x02014b50);
      put16(out, 20);  // made by: version 2.0
      entry_fields(out, e);
      for (int k = 0; k < 4; ++k) put16(out, 0);  // extra, comment, disk, internal attributes
      put32(out, 0);                              // external attributes
      put32(out, e.offset);
      out += e.name;
    }
    const size_t directory = out.size();
    put32(out, 0x06054b50);
    put16(out, 0);
    put16(out, 0);
    put16(out, uint16_t(entries_.size()));
    put16(out, uint16_t(entries_.size()));
    put32(out, uint32_t(directory));
    put32(out, uint32_t(offset_));
    put16(out, 0);  // comment length
    return out;
  }

  const char* encoder_name() const override { return "png"; }

 private:
  struct Entry {
    std::string name;
    uint32_t crc, size, offset;
  };
  static void put16(std::string& o, uint16_t v) {
    o += char(v & 0xff);
    o += char(v >> 8);
  }
  static void put32(std::string& o, uint32_t v) {
    put16(o, uint16_t(v & 0xffff));
    put16(o, uint16_t(v >> 16));
  }
  // What the local header and the central directory's record share, from "version needed" to the
  // name's length.
  static void entry_fields(std::string& o, const Entry& e) {
    put16(o, 20);      // version needed: 2.0
    put16(o, 0);       // flags
    put16(o, 0);       // stored
    put16(o, 0);       // time 00:00:00
    put16(o, 0x0021);  // date 1980-01-01
    put32(o, e.crc);
    put32(o, e.size);  // compressed
    put32(o, e.size);  // uncompressed
    put16(o, uint16_t(e.name.size()));
  }

  MovieSettings s_;
  std::vector<Entry> entries_;
  uint64_t offset_ = 0;
};

// The frames' 8-bit RGB, rows from the top, one frame after the other (as POST /api/render's
// ?format=rgb answers one).
class RgbWriter final : public MovieWriter {
 public:
  explicit RgbWriter(const MovieSettings& s) : bytes_(size_t(s.width) * size_t(s.height) * 3) {}
  std::string add(const uint8_t* rgb) override { return std::string(reinterpret_cast<const char*>(rgb), bytes_); }
  std::string finish() override { return std::string(); }
  const char* encoder_name() const override { return "rgb"; }

 private:
  size_t bytes_;
};

}  // namespace

std::unique_ptr<MovieWriter> open_image_movie_writer(const MovieSettings& s) {
  if (s.format == MovieFormat::Rgb) return std::make_unique<RgbWriter>(s);
  if (s.format != MovieFormat::PngZip) throw std::logic_error("open_image_movie_writer: a video format");
  return std::make_unique<PngZipWriter>(s);
}

}  // namespace peakcast::encode
