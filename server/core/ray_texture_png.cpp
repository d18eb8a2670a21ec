#include "core/ray_texture_png.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/scene_error.h"

OIIO_NAMESPACE_USING

namespace peakcast {
namespace {

[[noreturn]] void refuse(const std::string& key, const std::filesystem::path& path, const std::string& what) {
  throw SceneError(key + ": " + path.string() + ": " + what);
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
