#include "encode/png.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

OIIO_NAMESPACE_USING

namespace peakcast::encode {

std::vector<unsigned char> to_rgb8(const Image& img) {
  std::vector<unsigned char> out(size_t(img.width) * img.height * 3);
  for (size_t p = 0; p < size_t(img.width) * img.height; ++p)
    for (int c = 0; c < 3; ++c) {
      const float v = img.rgba[p * 4 + c];
      out[p * 3 + c] = (unsigned char)std::lround(std::clamp(std::isfinite(v) ? v : 0.f, 0.f, 1.f) * 255.f);
    }
  return out;
}

void write_png(const Image& img, const std::filesystem::path& path) {
  auto out = ImageOutput::create(path.string());
  if (!out) throw std::runtime_error(path.string() + ": cannot create PNG writer");
  ImageSpec spec(img.width, img.height, 3, TypeDesc::UINT8);
  if (!out->open(path.string(), spec)) throw std::runtime_error(path.string() + ": " + out->geterror());
  const auto bytes = to_rgb8(img);
  if (!out->write_image(TypeDesc::UINT8, bytes.data()))
    throw std::runtime_error(path.string() + ": " + out->geterror());
  out->close();
}

std::vector<unsigned char> encode_png(const unsigned char* rgb, int width, int height, int channels) {
  std::vector<unsigned char> out;
  Filesystem::IOVecOutput vec(out);
  auto writer = ImageOutput::create("png");
  if (!writer) throw std::runtime_error("no PNG writer");
  ImageSpec spec(width, height, channels, TypeDesc::UINT8);
  if (channels == 4) {
    spec.alpha_channel = 3;
    spec.attribute("oiio:UnassociatedAlpha", 1);  // straight already: OIIO would divide by alpha again
  }
  writer->set_ioproxy(&vec);
  if (!writer->open("memory.png", spec) || !writer->write_image(TypeDesc::UINT8, rgb))
    throw std::runtime_error("PNG encode failed: " + writer->geterror());
  writer->close();
  return out;
}

std::vector<unsigned char> to_rgba8_without_background(const Image& image, const float background[3]) {
  const size_t n = size_t(image.width) * size_t(image.height);
  std::vector<unsigned char> out(n * 4, 0);
  auto byte = [](float v) { return (unsigned char)std::lround(std::clamp(v, 0.f, 1.f) * 255.f); };
  for (size_t p = 0; p < n; ++p) {
    const float* px = &image.rgba[p * 4];
    const float a = std::clamp(px[3], 0.f, 1.f);
    if (!(a > 0.f)) continue;  // nothing hit: transparent black
    for (int c = 0; c < 3; ++c) out[p * 4 + c] = byte((px[c] - (1.f - a) * background[c]) / a);
    out[p * 4 + 3] = byte(a);
  }
  return out;
}

Image read_png(const std::filesystem::path& path) {
  auto in = ImageInput::open(path.string());
  if (!in) throw std::runtime_error(path.string() + ": cannot read image: " + OIIO::geterror());
  const ImageSpec& spec = in->spec();
  Image img(spec.width, spec.height);
  std::vector<float> buf(size_t(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, buf.data()))
    throw std::runtime_error(path.string() + ": " + in->geterror());
  for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p) {
    for (int c = 0; c < 3; ++c) img.rgba[p * 4 + c] = buf[p * spec.nchannels + std::min(c, spec.nchannels - 1)];
    img.rgba[p * 4 + 3] = 1.f;
  }
  return img;
}

}  // namespace peakcast::encode
