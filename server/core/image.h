// An RGBA float image, row 0 at the top (docs/scenes.md), plus the per-pixel sample counts.
#pragma once

#include <string>
#include <vector>

namespace peakcast {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgba;     // width * height * 4, rgb = final colour over the background, a = opacity
  std::vector<float> samples;  // samples taken per pixel's ray; -1 where the ray misses the box

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(size_t(w) * h * 4, 0.f), samples(size_t(w) * h, 0.f) {}
  float* pixel(int x, int y) { return &rgba[(size_t(y) * width + x) * 4]; }
  const float* pixel(int x, int y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

}  // namespace peakcast
