#include "core/ray_texture_mapping.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace peakcast {

glm::dvec2 view_uv(int x, int y, int width, int height) {
  return {(x + 0.5) / std::max(width, 1), (y + 0.5) / std::max(height, 1)};
}

glm::dvec2 volume_uv(const glm::dvec3& entry, const glm::dvec3& half) {
  constexpr double kPi = 3.14159265358979323846;
  const glm::dvec3 n = entry / glm::max(half, glm::dvec3(1e-300));
  const double len = glm::length(n);
  if (!(len > 0.0)) return {0.5, 0.5};
  return {0.5 + std::atan2(n.x, n.z) / (2.0 * kPi), std::acos(std::clamp(n.y / len, -1.0, 1.0)) / kPi};
}

std::array<double, 3> sample_ray_texture(const RayTexture& t, const glm::dvec2& uv) {
  const double fx = std::clamp(uv.x * t.width() - 0.5, 0.0, double(t.width() - 1));
  const double fy = std::clamp(uv.y * t.height() - 0.5, 0.0, double(t.height() - 1));
  const int x0 = int(std::floor(fx)), y0 = int(std::floor(fy));
  const int x1 = std::min(x0 + 1, t.width() - 1), y1 = std::min(y0 + 1, t.height() - 1);
  const double ax = fx - x0, ay = fy - y0;
  const auto a = t.at(x0, y0), b = t.at(x1, y0), c = t.at(x0, y1), d = t.at(x1, y1);
  std::array<double, 3> out{};
  for (int k = 0; k < 3; ++k)
    out[size_t(k)] =
        (1 - ay) * ((1 - ax) * a[size_t(k)] + ax * b[size_t(k)]) + ay * ((1 - ax) * c[size_t(k)] + ax * d[size_t(k)]);
  return out;
}

}  // namespace peakcast
