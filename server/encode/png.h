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
// PNG bytes in memory (REST stills).
std::vector<unsigned char> encode_png(const unsigned char* rgb, int width, int height);

}  // namespace peakcast::encode
