// Where a ray reads the ray texture (Raspe & Müller 2008 §3.1), mirrored by
// shaders/ray_texture.glsl:
//   view    u = (x + 0.5) / width, v = (y + 0.5) / height: the pixel centre over the image,
//           u to the right, v down (row 0 at the top);
//   volume  the direction of the ray's entry point from the box centre, in box units
//           (n = p / half-extent, each axis in [-1, 1]): u = 1/2 + atan2(n.x, n.z) / 2 pi,
//           v = acos(n.y / |n|) / pi, so v = 0 at the box's +y pole and u runs once around y.
//           An edit stays on the same part of the volume's surface when the camera moves.
// The texture is read with bilinear filtering between texel centres, clamped at the edges
// (GL_LINEAR, GL_CLAMP_TO_EDGE).
#pragma once

#include <array>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "core/ray_texture.h"

namespace peakcast {

glm::dvec2 view_uv(int x, int y, int width, int height);
// `entry`: the entry point in box-centred coordinates; `half`: the box's half extent.
glm::dvec2 volume_uv(const glm::dvec3& entry, const glm::dvec3& half);
// step multiplier, termination, blend at uv.
std::array<double, 3> sample_ray_texture(const RayTexture& t, const glm::dvec2& uv);

}  // namespace peakcast
