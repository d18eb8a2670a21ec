// What a ray-cast draw produces and how it is asked for: the output format (float for tests,
// the CLI and reference comparisons; 8-bit RGB for streamed frames), and an optional tile (a
// pixel sub-rectangle of the full image) so a large still can be rendered in pieces between
// interactive frames. Tile pixels equal the same pixels of a full render exactly.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "render/variant.h"

namespace peakcast::render {

enum class RenderOutput {
  Float,  // RGBA32F over the background + per-pixel sample counts (an Image)
  Rgb8,   // 8-bit RGB over the background, quantised on the GPU exactly like encode::to_rgb8
};

// A rectangle in full-image pixels, row 0 at the top.
struct PixelRect {
  int x = 0, y = 0, w = 0, h = 0;
  bool operator==(const PixelRect&) const = default;
  std::string to_string() const;
};

struct RenderRequest {
  RenderPath path = RenderPath::Fragment;
  RenderOutput output = RenderOutput::Float;
  // Rgb8 only: also read back the per-pixel sample counts (4 more bytes per pixel) so the stats
  // carry samples per ray. Float always reads them (they are part of the Image).
  bool sample_stats = false;
  std::optional<PixelRect> tile;  // default: the whole image
};

// Packed 8-bit RGB, row 0 at the top, no row padding: what the JPEG/PNG encoders take.
struct Rgb8Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // width * height * 3
  Rgb8Image() = default;
  Rgb8Image(int w, int h) : width(w), height(h), rgb(size_t(w) * h * 3, 0) {}
};

struct RenderResult {
  PixelRect rect;  // the pixels drawn, in full-image pixels
  Image image;     // RenderOutput::Float (rect.w x rect.h)
  Rgb8Image rgb8;  // RenderOutput::Rgb8 (rect.w x rect.h)
};

// Throws std::invalid_argument naming the limit unless `r` is a non-empty rectangle inside a
// width x height image.
void check_rect(const PixelRect& r, int width, int height);
// Tiles of at most tile_w x tile_h covering a width x height image, row by row from the top
// left; the last tile of a row/column is narrower. Throws for non-positive sizes.
std::vector<PixelRect> tile_grid(int width, int height, int tile_w, int tile_h);
// Copies a tile's pixels (and sample counts) into the full image at `r`; throws when the tile's
// size differs from r or r is outside the image.
void place_tile(Image& full, const PixelRect& r, const Image& tile);
void place_tile(Rgb8Image& full, const PixelRect& r, const Rgb8Image& tile);

}  // namespace peakcast::render
