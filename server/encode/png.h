// PNG through OpenImageIO: 8-bit RGB, row 0 at the top.
#pragma once

#include <filesystem>
#include <vector>

#include "core/image.h"

namespace peakcast::encode {

void write_png(const Image& image, const std::filesystem::path& path);
Image read_png(const std::filesystem::path& path);  // throws std::runtime_error
// 8-bit RGB bytes, row 0 first, each channel round(clamp(v, 0, 1) * 255).
std::vector<unsigned char> to_rgb8(const Image& image);
// PNG bytes in memory (REST stills): `channels` 3 (RGB) or 4 (RGBA, straight alpha).
std::vector<unsigned char> encode_png(const unsigned char* rgb, int width, int height, int channels = 3);
// 8-bit RGBA, straight (not premultiplied) alpha, with the background taken out: each pixel's
// colour over `background` (Image::rgba) becomes the colour the volume alone gave it, and its
// opacity the alpha (0 where nothing was hit: transparent).
std::vector<unsigned char> to_rgba8_without_background(const Image& image, const float background[3]);

}  // namespace peakcast::encode
