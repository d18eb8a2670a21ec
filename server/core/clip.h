// Clipping (docs/scenes.md, render.clip): an axis-aligned crop box and one free plane, in world
// units, either optional; the side the plane's normal points to is kept. Every ray caster (the
// CPU reference, the CPU backend, GL, on bricks too) cuts its span through the volume's box to
// what the clip keeps, before its sample lattice is laid: the first sample is at the clipped
// entry, as at the box's entry without a clip, so a box that covers the volume changes nothing
// and clipped space contributes nothing.
#pragma once

#include <algorithm>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

namespace peakcast {

struct ClipSettings {
  bool box = false;
  glm::dvec3 box_lo{0.0}, box_hi{0.0};  // world; lo <= hi per axis
  bool plane = false;
  glm::dvec3 point{0.0}, normal{0.0, 0.0, 1.0};  // world; normal of unit length
  bool active() const { return box || plane; }
};

ClipSettings parse_clip(const nlohmann::json& j);  // throws SceneError naming the key
nlohmann::json to_json(const ClipSettings& c);

// The clip relative to the volume box's centre (where the ray casters put their rays), in the
// ray caster's precision. Plane: keeps dot(p, normal) >= offset.
template <typename Vec, typename T>
struct CenteredClip {
  bool box = false, plane = false;
  Vec lo{T(0)}, hi{T(0)}, normal{T(0)};
  T offset = T(0);
};

template <typename Vec, typename T>
CenteredClip<Vec, T> center_clip(const ClipSettings& c, const glm::dvec3& box_center) {
  CenteredClip<Vec, T> k;
  k.box = c.box;
  k.plane = c.plane;
  k.lo = Vec(c.box_lo - box_center);
  k.hi = Vec(c.box_hi - box_center);
  k.normal = Vec(c.normal);
  k.offset = T(glm::dot(c.point - box_center, c.normal));
  return k;
}

// Cuts the ray span [t0, t1] (o + t d) to what the clip keeps; false when nothing is left.
// The reference's; the GL and CPU backends share clip_span in shaders/ray/ray_setup.glsl.
template <typename Vec, typename T>
bool clip_span(const CenteredClip<Vec, T>& k, const Vec& o, const Vec& d, T& t0, T& t1) {
  if (k.box) {
    for (int a = 0; a < 3; ++a) {
      if (d[a] == T(0)) {
        if (o[a] < k.lo[a] || o[a] > k.hi[a]) return false;
        continue;
      }
      const T ta = (k.lo[a] - o[a]) / d[a], tb = (k.hi[a] - o[a]) / d[a];
      t0 = std::max(t0, std::min(ta, tb));
      t1 = std::min(t1, std::max(ta, tb));
    }
  }
  if (k.plane) {
    const T dn = k.normal[0] * d[0] + k.normal[1] * d[1] + k.normal[2] * d[2];
    const T on = k.normal[0] * o[0] + k.normal[1] * o[1] + k.normal[2] * o[2] - k.offset;  // kept where >= 0
    if (dn > T(0))
      t0 = std::max(t0, -on / dn);
    else if (dn < T(0))
      t1 = std::min(t1, -on / dn);
    else if (on < T(0))
      return false;
  }
  return t0 <= t1;
}

}  // namespace peakcast
