#include "core/ray_texture_png.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

#include "core/scene_error.h"

OIIO_NAMESPACE_USING

namespace peakcast {
namespace {

[[noreturn]] void refuse(const std::string& key, const std::filesystem::path& path, const std::string& what) {
  throw SceneError(key + ": " + path.string() + ": " + what);
}

uint32_t be32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

constexpr std::uintmax_t kMaxPngBytes = 64ull << 20;  // a 2048^2 16-bit RGBA PNG is at most ~32 MiB

// Bytes of a PNG's filtered image data: one filter byte then the packed samples per row, per
// Adam7 pass when interlaced.
struct PngRows {
  std::vector<size_t> row_bytes;  // every row's length in order, filter byte included
  size_t total = 0;
};
PngRows png_rows(uint32_t w, uint32_t h, int bits_per_pixel, bool interlaced) {
  PngRows r;
  auto add = [&](uint64_t cols, uint64_t rows) {
    if (cols == 0) return;
    const size_t bytes = 1 + size_t((cols * uint64_t(bits_per_pixel) + 7) / 8);
    for (uint64_t y = 0; y < rows; ++y) r.row_bytes.push_back(bytes), r.total += bytes;
  };
  if (!interlaced) {
    add(w, h);
    return r;
  }
  static const int pass[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8}, {2, 0, 4, 4},
                                 {0, 2, 2, 4}, {1, 0, 2, 2}, {0, 1, 1, 2}};
  for (const auto& p : pass) {
    const uint64_t cols = w > uint32_t(p[0]) ? (w - p[0] + p[2] - 1) / p[2] : 0;
    const uint64_t rows = h > uint32_t(p[1]) ? (h - p[1] + p[3] - 1) / p[3] : 0;
    if (rows) add(cols, rows);
  }
  return r;
}

// The whole file, checked before a decoder sees it: the signature; IHDR first, within the size
// limit and of a known kind; every chunk inside the file with its CRC right; IEND at the end; and
// the image data inflating to exactly the rows IHDR promises, each with a valid filter byte.
// libpng reports a truncated or corrupt file by longjmp out of OpenImageIO's reader, which leaks
// what that reader held; refused here, such files never reach it. The decoder then reads these
// bytes, not the path again.
std::vector<unsigned char> checked_png_bytes(const std::string& key, const std::filesystem::path& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) refuse(key, path, "cannot read: " + ec.message());
  if (size > kMaxPngBytes)
    refuse(key, path, "is " + std::to_string(size) + " bytes; a ray-texture PNG is at most 64 MiB");
  std::vector<unsigned char> b(size);
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(b.data()), std::streamsize(size))) refuse(key, path, "cannot read");
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size < 8 || std::memcmp(b.data(), sig, 8) != 0) refuse(key, path, "is not PNG (no PNG signature)");
  size_t at = 8;
  PngRows rows;
  std::vector<unsigned char> idat;
  while (true) {
    if (size - at < 12) refuse(key, path, "is truncated (a chunk header runs past the end of the file)");
    const uint32_t len = be32(&b[at]);
    const std::string type(reinterpret_cast<const char*>(&b[at + 4]), 4);
    if (len > size - at - 12) refuse(key, path, "is truncated (chunk " + type + " runs past the end of the file)");
    const uint32_t crc = uint32_t(crc32(crc32(0L, Z_NULL, 0), &b[at + 4], uInt(len + 4)));
    if (crc != be32(&b[at + 8 + len])) refuse(key, path, "is corrupt (chunk " + type + " fails its CRC)");
    const unsigned char* data = &b[at + 8];
    if (at == 8) {
      if (type != "IHDR" || len != 13) refuse(key, path, "is corrupt (it does not start with an IHDR chunk)");
      const uint32_t w = be32(data), h = be32(data + 4);
      if (w < 1 || h < 1 || w > uint32_t(kMaxRayTextureSide) || h > uint32_t(kMaxRayTextureSide))
        refuse(key, path,
               std::to_string(w) + "x" + std::to_string(h) + " is the wrong size: each side must be 1.." +
                   std::to_string(kMaxRayTextureSide));
      const int depth = data[8], colour = data[9];
      const int samples = colour == 0 ? 1 : colour == 2 ? 3 : colour == 3 ? 1 : colour == 4 ? 2 : colour == 6 ? 4 : 0;
      const bool depth_ok = depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16;
      if (!samples || !depth_ok || data[10] != 0 || data[11] != 0 || data[12] > 1)
        refuse(key, path, "is corrupt (IHDR names no PNG image kind)");
      rows = png_rows(w, h, depth * samples, data[12] == 1);
    } else if (type == "IDAT") {
      idat.insert(idat.end(), data, data + len);
    } else if (type == "IEND") {
      break;
    }
    at += 12 + size_t(len);
  }
  // Inflate the image data: exactly the promised rows, no more, each starting with filter 0..4.
  std::vector<unsigned char> raw(rows.total + 1);
  z_stream z{};
  if (inflateInit(&z) != Z_OK) refuse(key, path, "cannot inflate");
  z.next_in = idat.data();
  z.avail_in = uInt(idat.size());
  z.next_out = raw.data();
  z.avail_out = uInt(raw.size());
  const int rc = inflate(&z, Z_FINISH);
  const size_t got = raw.size() - z.avail_out;
  inflateEnd(&z);
  if (rc != Z_STREAM_END || got != rows.total)
    refuse(key, path,
           "is corrupt (its image data does not inflate to the " + std::to_string(rows.total) +
               " bytes its header promises)");
  size_t row = 0;
  for (size_t len : rows.row_bytes) {
    if (raw[row] > 4) refuse(key, path, "is corrupt (a row has filter type " + std::to_string(raw[row]) + ")");
    row += len;
  }
  return b;
}

template <class T>
std::vector<float> channels_of(const std::vector<T>& px, size_t n, int stride, double max) {
  const double h = (max + 1.0) / 2.0;
  std::vector<float> t(n * 3);
  for (size_t i = 0; i < n; ++i) {
    const double r = px[i * size_t(stride)], g = px[i * size_t(stride) + 1], b = px[i * size_t(stride) + 2];
    t[i * 3] = float(std::clamp(std::pow(8.0, (r - h) / h), kMinStepMultiplier, kMaxStepMultiplier));
    t[i * 3 + 1] = float(g / max);
    t[i * 3 + 2] = float(std::clamp((b - h) / h, -1.0, 1.0));
  }
  return t;
}

}  // namespace

std::shared_ptr<const RayTextureImage> read_ray_texture_png(const std::filesystem::path& path, const std::string& key) {
  const std::vector<unsigned char> bytes = checked_png_bytes(key, path);
  // Alpha is ignored, so it must not be multiplied into R, G, B (OIIO's default for PNG).
  ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  // The checked bytes, as PNG. OIIO 2.4's PNG reader takes an IOProxy only through this
  // attribute (the open() argument gives "could not open file").
  Filesystem::IOMemReader memory(bytes.data(), bytes.size());
  void* proxy = &memory;
  config.attribute("oiio:ioproxy", TypeDesc::PTR, &proxy);
  auto in = ImageInput::open("ray_texture.png", &config);
  if (!in) refuse(key, path, "cannot read as an image: " + OIIO::geterror());
  const ImageSpec& spec = in->spec();
  if (std::string(in->format_name()) != "png") refuse(key, path, std::string("is ") + in->format_name() + ", not PNG");
  if (spec.width < 1 || spec.height < 1 || spec.width > kMaxRayTextureSide || spec.height > kMaxRayTextureSide ||
      spec.depth != 1)
    refuse(key, path,
           std::to_string(spec.width) + "x" + std::to_string(spec.height) +
               " is the wrong size: each side must be 1.." + std::to_string(kMaxRayTextureSide));
  if (spec.nchannels < 3)
    refuse(key, path,
           "has " + std::to_string(spec.nchannels) + " channel(s); it needs R, G, B (step, termination, blend)");
  const bool wide = spec.format.size() > 1;
  const size_t n = size_t(spec.width) * size_t(spec.height);
  auto image = std::make_shared<RayTextureImage>();
  image->width = spec.width;
  image->height = spec.height;
  const int nc = spec.nchannels;
  if (wide) {
    std::vector<uint16_t> px(n * size_t(nc));
    if (!in->read_image(0, 0, 0, nc, TypeDesc::UINT16, px.data())) refuse(key, path, in->geterror());
    image->texels = channels_of(px, n, nc, 65535.0);
  } else {
    std::vector<uint8_t> px(n * size_t(nc));
    if (!in->read_image(0, 0, 0, nc, TypeDesc::UINT8, px.data())) refuse(key, path, in->geterror());
    image->texels = channels_of(px, n, nc, 255.0);
  }
  return image;
}

void write_ray_texture_png(const RayTexture& texture, const std::filesystem::path& path) {
  const auto& t = texture.texels();
  std::vector<uint8_t> px(t.size());
  for (size_t i = 0; i < t.size(); i += 3) {
    px[i] = uint8_t(std::lround(std::clamp(128.0 + 128.0 * std::log(double(t[i])) / std::log(8.0), 0.0, 255.0)));
    px[i + 1] = uint8_t(std::lround(std::clamp(double(t[i + 1]) * 255.0, 0.0, 255.0)));
    px[i + 2] = uint8_t(std::lround(std::clamp(128.0 + 128.0 * double(t[i + 2]), 0.0, 255.0)));
  }
  auto out = ImageOutput::create(path.string());
  if (!out) throw std::runtime_error(path.string() + ": cannot create a PNG writer");
  ImageSpec spec(texture.width(), texture.height(), 3, TypeDesc::UINT8);
  if (!out->open(path.string(), spec) || !out->write_image(TypeDesc::UINT8, px.data()))
    throw std::runtime_error(path.string() + ": " + out->geterror());
  out->close();
}

std::shared_ptr<const RayTextureSpec> load_ray_texture_png(const std::shared_ptr<const RayTextureSpec>& spec,
                                                           const PngLocator& locate) {
  if (!spec || spec->png.empty() || spec->image) return spec;
  if (!locate) throw SceneError("render.ray_texture.png: PNG ray textures cannot be read here");
  std::filesystem::path path;
  try {
    path = locate(spec->png);
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    throw SceneError(std::string("render.ray_texture.png: ") + e.what());
  }
  auto loaded = std::make_shared<RayTextureSpec>(*spec);
  loaded->image = read_ray_texture_png(path);
  loaded->width = loaded->image->width;
  loaded->height = loaded->image->height;
  count_work(*loaded);  // the strokes' cost at the PNG's size
  return loaded;
}

}  // namespace peakcast
