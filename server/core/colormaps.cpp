#include "core/colormaps.h"

#include <algorithm>
#include <stdexcept>

namespace peakcast {

const std::vector<Colormap>& colormaps() {
  static const std::vector<Colormap> maps = {
      {"viridis",
       {{68, 1, 84},
        {72, 36, 117},
        {64, 67, 135},
        {52, 95, 141},
        {41, 120, 142},
        {32, 144, 141},
        {34, 168, 132},
        {67, 191, 112},
        {122, 210, 81},
        {188, 223, 39},
        {253, 231, 37}}},
      {"magma",
       {{0, 0, 4},
        {28, 16, 68},
        {79, 18, 123},
        {129, 37, 129},
        {181, 54, 122},
        {229, 80, 100},
        {251, 135, 97},
        {254, 194, 135},
        {252, 253, 191}}},
      {"coolwarm",
       {{59, 76, 192},
        {98, 130, 234},
        {141, 176, 254},
        {184, 208, 249},
        {221, 221, 221},
        {245, 196, 173},
        {244, 154, 123},
        {222, 96, 77},
        {180, 4, 38}}},
      {"grey", {{0, 0, 0}, {255, 255, 255}}},
  };
  return maps;
}

glm::dvec3 colormap(const std::string& name, double t) {
  for (const Colormap& m : colormaps()) {
    if (name != m.name) continue;
    t = std::clamp(t, 0.0, 1.0) * double(m.stops.size() - 1);
    const size_t i = std::min(size_t(t), m.stops.size() - 2);
    const double f = t - double(i);
    glm::dvec3 c;
    for (int ch = 0; ch < 3; ++ch) c[ch] = ((1 - f) * m.stops[i][ch] + f * m.stops[i + 1][ch]) / 255.0;
    return c;
  }
  throw std::invalid_argument("no colour map '" + name + "' (viridis, magma, coolwarm, grey)");
}

}  // namespace peakcast
