// The named colour maps (sRGB stops, evenly spaced over [0, 1]): matplotlib's viridis and magma,
// Moreland's cool-warm, and grey. The automatic TF colours by viridis; scripts build TFs from
// any of them (GET /api/colormaps, docs/rest.md).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace peakcast {

struct Colormap {
  const char* name;
  std::vector<std::array<int, 3>> stops;  // 8-bit sRGB, evenly spaced
};

const std::vector<Colormap>& colormaps();
// The map's colour at t in [0, 1] (clamped), linear between stops, in [0, 1]. Throws
// std::invalid_argument for a name that is none of colormaps().
glm::dvec3 colormap(const std::string& name, double t);

}  // namespace peakcast
