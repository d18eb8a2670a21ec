#include "render/frame.h"

#include <algorithm>
#include <stdexcept>

namespace peakcast::render {

std::string PixelRect::to_string() const {
  return std::to_string(w) + "x" + std::to_string(h) + "+" + std::to_string(x) + "+" + std::to_string(y);
}

void check_rect(const PixelRect& r, int width, int height) {
  if (r.w <= 0 || r.h <= 0)
    throw std::invalid_argument("tile " + r.to_string() + ": width and height must be at least 1 pixel");
  // 64-bit sums: x + w must not overflow for any int input.
  if (r.x < 0 || r.y < 0 || int64_t(r.x) + r.w > width || int64_t(r.y) + r.h > height)
    throw std::invalid_argument("tile " + r.to_string() + " is outside the " + std::to_string(width) + "x" +
                                std::to_string(height) + " image");
}

std::vector<PixelRect> tile_grid(int width, int height, int tile_w, int tile_h) {
  if (width <= 0 || height <= 0 || tile_w <= 0 || tile_h <= 0)
    throw std::invalid_argument("tile_grid: image and tile sizes must be positive (image " + std::to_string(width) +
                                "x" + std::to_string(height) + ", tile " + std::to_string(tile_w) + "x" +
                                std::to_string(tile_h) + ")");
  std::vector<PixelRect> out;
  for (int y = 0; y < height; y += tile_h)
    for (int x = 0; x < width; x += tile_w)
      out.push_back({x, y, std::min(tile_w, width - x), std::min(tile_h, height - y)});
  return out;
}

namespace {
void check_place(const PixelRect& r, int full_w, int full_h, int tile_w, int tile_h) {
  check_rect(r, full_w, full_h);
  if (tile_w != r.w || tile_h != r.h)
    throw std::invalid_argument("place_tile: tile image is " + std::to_string(tile_w) + "x" + std::to_string(tile_h) +
                                ", rectangle " + r.to_string());
}
}  // namespace

void place_tile(Image& full, const PixelRect& r, const Image& tile) {
  check_place(r, full.width, full.height, tile.width, tile.height);
  for (int row = 0; row < r.h; ++row) {
    std::copy_n(tile.pixel(0, row), size_t(r.w) * 4, full.pixel(r.x, r.y + row));
    std::copy_n(&tile.samples[size_t(row) * r.w], r.w, &full.samples[size_t(r.y + row) * full.width + r.x]);
  }
}

void place_tile(Rgb8Image& full, const PixelRect& r, const Rgb8Image& tile) {
  check_place(r, full.width, full.height, tile.width, tile.height);
  for (int row = 0; row < r.h; ++row)
    std::copy_n(&tile.rgb[size_t(row) * r.w * 3], size_t(r.w) * 3,
                &full.rgb[(size_t(r.y + row) * full.width + r.x) * 3]);
}

}  // namespace peakcast::render
