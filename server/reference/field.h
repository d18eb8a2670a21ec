// CPU twins of shaders/common_sampling.glsl in double precision: trilinear and cubic B-spline
// reconstruction with clamp-to-edge, and the central-difference gradient. Positions in voxel
// coordinates (voxel i at i); values physical.
#pragma once

#include <glm/vec3.hpp>

#include "core/scene.h"
#include "core/volume.h"

namespace peakcast::reference {

double trilinear(const Volume& v, const glm::dvec3& x);
double bspline(const Volume& v, const glm::dvec3& x);
inline double sample(const Volume& v, const glm::dvec3& x, Filter f) {
  return f == Filter::Tricubic ? bspline(v, x) : trilinear(v, x);
}
// Per world unit, physical units.
glm::dvec3 gradient(const Volume& v, const glm::dvec3& x, Filter f);

}  // namespace peakcast::reference
