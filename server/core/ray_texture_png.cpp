#include "core/ray_texture_png.h"

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

uint32_t be32(const unsigned char* p) { return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3]; }

constexpr std::uintmax_t kMaxPngBytes = 64ull << 20;  // a 2048^2 16-bit RGBA PNG is at most ~32 MiB

// The file's chunk structure, checked before a decoder sees it: the signature, IHDR first and
// within the size limit, every chunk inside the file with its CRC right, IEND at the end.
// libpng reports a truncated or corrupt file by longjmp out of OpenImageIO's reader, which
// leaks what that reader held; refused here, such files never reach it.
void check_png_structure(const std::string& key, const std::filesystem::path& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) refuse(key, path, "cannot read: " + ec.message());
  if (size > kMaxPngBytes) refuse(key, path, "is " + std::to_string(size) + " bytes; a ray-texture PNG is at most 64 MiB");
  std::vector<unsigned char> b(size);
  std::ifstream in(path, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(b.data()), std::streamsize(size))) refuse(key, path, "cannot read");
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size < 8 || std::memcmp(b.data(), sig, 8) != 0) refuse(key, path, "is not PNG (no PNG signature)");
  size_t at = 8;
  bool first = true;
  while (true) {
    if (size - at < 12) refuse(key, path, "is truncated (a chunk header runs past the end of the file)");
    const uint32_t len = be32(&b[at]);
    const std::string type(reinterpret_cast<const char*>(&b[at + 4]), 4);
    if (len > size - at - 12) refuse(key, path, "is truncated (chunk " + type + " runs past the end of the file)");
    const uint32_t crc = uint32_t(crc32(crc32(0L, Z_NULL, 0), &b[at + 4], uInt(len + 4)));
    if (crc != be32(&b[at + 8 + len])) refuse(key, path, "is corrupt (chunk " + type + " fails its CRC)");
    if (first) {
      if (type != "IHDR" || len != 13) refuse(key, path, "is corrupt (it does not start with an IHDR chunk)");
      const uint32_t w = be32(&b[at + 8]), h = be32(&b[at + 12]);
      if (w < 1 || h < 1 || w > uint32_t(kMaxRayTextureSide) || h > uint32_t(kMaxRayTextureSide))
        refuse(key, path, std::to_string(w) + "x" + std::to_string(h) + " is the wrong size: each side must be 1.." +
                              std::to_string(kMaxRayTextureSide));
      first = false;
    }
    at += 12 + size_t(len);
    if (type == "IEND") return;
  }
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
  check_png_structure(key, path);
  // Alpha is ignored, so it must not be multiplied into R, G, B (OIIO's default for PNG).
  ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = ImageInput::open(path.string(), &config);
  if (!in) refuse(key, path, "cannot read as an image: " + OIIO::geterror());
  const ImageSpec& spec = in->spec();
  if (std::string(in->format_name()) != "png") refuse(key, path, std::string("is ") + in->format_name() + ", not PNG");
  if (spec.width < 1 || spec.height < 1 || spec.width > kMaxRayTextureSide || spec.height > kMaxRayTextureSide ||
      spec.depth != 1)
    refuse(key, path,
           std::to_string(spec.width) + "x" + std::to_string(spec.height) + " is the wrong size: each side must be 1.." +
               std::to_string(kMaxRayTextureSide));
  if (spec.nchannels < 3)
    refuse(key, path, "has " + std::to_string(spec.nchannels) + " channel(s); it needs R, G, B (step, termination, blend)");
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
  return loaded;
}

}  // namespace peakcast
