#include "core/clip.h"

#include <cmath>

#include "core/json_fields.h"

namespace peakcast {

using namespace json_fields;

ClipSettings parse_clip(const nlohmann::json& j) {
  if (!j.is_object()) fail("render.clip", "must be an object with \"box\" and/or \"plane\"");
  only_keys(j, "render.clip", {"box", "plane"});
  ClipSettings c;
  if (j.contains("box")) {
    const auto& b = j["box"];
    if (!b.is_array() || b.size() != 2) fail("render.clip.box", "must be [[x0, y0, z0], [x1, y1, z1]] (world units)");
    c.box = true;
    c.box_lo = vec3(b[0], "render.clip.box[0]");
    c.box_hi = vec3(b[1], "render.clip.box[1]");
    for (int a = 0; a < 3; ++a)
      if (c.box_lo[a] > c.box_hi[a]) fail("render.clip.box", "the first corner must be the low one on every axis");
  }
  if (j.contains("plane")) {
    const auto& p = j["plane"];
    if (!p.is_object()) fail("render.clip.plane", "must be {\"point\": [x, y, z], \"normal\": [x, y, z]}");
    only_keys(p, "render.clip.plane", {"point", "normal"});
    if (!p.contains("point") || !p.contains("normal")) fail("render.clip.plane", "needs point and normal");
    c.plane = true;
    c.point = vec3(p["point"], "render.clip.plane.point");
    const glm::dvec3 n = vec3(p["normal"], "render.clip.plane.normal");
    const double len = glm::length(n);
    if (!(len > 0)) fail("render.clip.plane.normal", "must not be zero");
    c.normal = n / len;
  }
  return c;
}

nlohmann::json to_json(const ClipSettings& c) {
  nlohmann::json j = nlohmann::json::object();
  if (c.box) j["box"] = {{c.box_lo.x, c.box_lo.y, c.box_lo.z}, {c.box_hi.x, c.box_hi.y, c.box_hi.z}};
  if (c.plane)
    j["plane"] = {{"point", {c.point.x, c.point.y, c.point.z}}, {"normal", {c.normal.x, c.normal.y, c.normal.z}}};
  return j;
}

}  // namespace peakcast
