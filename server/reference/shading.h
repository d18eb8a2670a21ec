// The reference's shading: the same model as shaders/ray/shading.glsl, in double.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace peakcast::reference {

constexpr double kAmbient = 0.3, kDiffuse = 0.6, kSpecular = 0.25, kShininess = 32.0;

// `gradient` in TF coordinates per world unit; `min_spacing` the volume's smallest spacing.
inline glm::dvec3 shade(const glm::dvec3& rgb, const glm::dvec3& gradient, const glm::dvec3& view_dir,
                        double min_spacing) {
  const double len = glm::length(gradient);
  if (len * min_spacing < 1e-5) return rgb;
  const double ndotl = std::abs(glm::dot(gradient / len, -view_dir));
  return rgb * (kAmbient + kDiffuse * ndotl) + glm::dvec3(kSpecular * std::pow(ndotl, kShininess));
}

}  // namespace peakcast::reference
