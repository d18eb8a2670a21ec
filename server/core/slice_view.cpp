#include "core/slice_view.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace peakcast {
namespace {

glm::dvec3 vec3_of(const nlohmann::json& j, const std::string& key) {
  if (!j.is_array() || j.size() != 3 || !std::all_of(j.begin(), j.end(), [](auto& x) { return x.is_number(); }))
    throw SceneError(key + ": 3 numbers");
  glm::dvec3 v{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) throw SceneError(key + ": finite numbers");
  return v;
}

glm::dvec3 unit(int axis, double sign = 1.0) {
  glm::dvec3 e{0.0};
  e[axis] = sign;
  return e;
}

// Where the slice lies and how it is seen: world = p0 + u right + v up, pixels covering
// [u0, u1] x [v0, v1] at du x dv (one voxel each for an axis slice).
struct Frame {
  glm::dvec3 p0{0.0}, right{1, 0, 0}, up{0, 1, 0};
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0, du = 1, dv = 1;
  int64_t index = -1;
};

// The in-plane axis nearest to `want` projected off `axis` (signed), or -1.
int snapped(const glm::dvec3& want, int axis, double& sign) {
  int best = -1;
  for (int a = 0; a < 3; ++a)
    if (a != axis && std::abs(want[a]) > 1e-9 && (best < 0 || std::abs(want[a]) > std::abs(want[best]))) best = a;
  if (best >= 0) sign = want[best] > 0 ? 1.0 : -1.0;
  return best;
}

Frame axis_frame(const Volume& v, const SliceRequest& s, const glm::dvec3& want_up) {
  const int axis = s.axis;
  const Dims full = v.full_dims[0] > 0 ? v.full_dims : v.dims();
  if (s.index < 0 || s.index >= full[axis])
    throw SceneError("slice.index: " + std::to_string(s.index) + " is outside 0.." + std::to_string(full[axis] - 1) +
                     " (the volume's voxels along " + std::string(1, char('x' + axis)) + ")");
  Frame f;
  const double ratio = v.full_spacing[axis] > 0 ? v.full_spacing[axis] / v.spacing[axis] : 1.0;  // a coarser level
  f.index = std::clamp<int64_t>(int64_t(std::floor(double(s.index) * ratio)), 0, v.dims()[axis] - 1);
  double su = 1.0;
  int au = snapped(want_up, axis, su);
  if (au < 0) au = snapped(axis == 1 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0), axis, su);
  f.up = unit(au, su);
  f.right = glm::cross(-unit(axis), f.up);  // seen from the axis' positive side
  const int ar = 3 - axis - au;
  f.p0 = v.origin + unit(axis) * (double(f.index) * v.spacing[axis]);
  const double last_u = glm::dot(unit(ar) * (double(v.dims()[ar] - 1) * v.spacing[ar]), f.right);
  const double last_v = glm::dot(unit(au) * (double(v.dims()[au] - 1) * v.spacing[au]), f.up);
  f.du = v.spacing[ar];
  f.dv = v.spacing[au];
  f.u0 = std::min(0.0, last_u) - f.du / 2;
  f.u1 = std::max(0.0, last_u) + f.du / 2;
  f.v0 = std::min(0.0, last_v) - f.dv / 2;
  f.v1 = std::max(0.0, last_v) + f.dv / 2;
  return f;
}

Frame plane_frame(const Volume& v, const SliceRequest& s, glm::dvec3 want_up) {
  const double len = glm::length(s.normal);
  if (!(len > 0)) throw SceneError("slice.plane.normal: must not be zero");
  const glm::dvec3 n = s.normal / len;
  Frame f;
  f.p0 = s.point;
  if (glm::length(glm::cross(want_up, n)) < 1e-6)
    want_up = std::abs(n.z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  f.up = glm::normalize(want_up - glm::dot(want_up, n) * n);
  f.right = glm::cross(-n, f.up);
  f.du = f.dv = std::min({v.spacing.x, v.spacing.y, v.spacing.z});
  f.u0 = f.v0 = INFINITY;
  f.u1 = f.v1 = -INFINITY;
  for (int c = 0; c < 8; ++c) {  // the box's corners on the plane
    glm::dvec3 corner = v.origin;
    for (int a = 0; a < 3; ++a)
      if (c >> a & 1) corner[a] += double(v.dims()[a] - 1) * v.spacing[a];
    const double cu = glm::dot(corner - f.p0, f.right), cv = glm::dot(corner - f.p0, f.up);
    f.u0 = std::min(f.u0, cu - f.du / 2), f.u1 = std::max(f.u1, cu + f.du / 2);
    f.v0 = std::min(f.v0, cv - f.dv / 2), f.v1 = std::max(f.v1, cv + f.dv / 2);
  }
  return f;
}

}  // namespace

SliceRequest parse_slice(const nlohmann::json& j) {
  if (!j.is_object()) throw SceneError("slice: an object, {\"axis\": \"z\", \"index\": k} or {\"plane\": {...}}");
  SliceRequest s;
  for (const auto& [key, _] : j.items())
    if (key != "axis" && key != "index" && key != "plane" && key != "window")
      throw SceneError("slice: unknown key '" + key + "' (axis, index, plane, window)");
  if (j.contains("axis") == j.contains("plane")) throw SceneError("slice: one of axis (with index) or plane");
  if (j.contains("axis")) {
    const auto& a = j["axis"];
    if (!a.is_string() || (a != "x" && a != "y" && a != "z")) throw SceneError("slice.axis: \"x\", \"y\" or \"z\"");
    s.axis = a.get<std::string>()[0] - 'x';
    if (!j.contains("index") || !j["index"].is_number_integer())
      throw SceneError("slice.index: an integer voxel index");
    s.index = j["index"].get<int64_t>();
  } else {
    const auto& p = j["plane"];
    if (!p.is_object() || !p.contains("point") || !p.contains("normal") || p.size() != 2)
      throw SceneError("slice.plane: {\"point\": [x, y, z], \"normal\": [x, y, z]}");
    s.point = vec3_of(p["point"], "slice.plane.point");
    s.normal = vec3_of(p["normal"], "slice.plane.normal");
  }
  if (j.contains("window")) {
    const auto& w = j["window"];
    if (!w.is_array() || w.size() != 2 || !w[0].is_number() || !w[1].is_number() ||
        !(w[1].get<double>() > w[0].get<double>()))
      throw SceneError("slice.window: [lo, hi] with lo < hi");
    s.window = std::array<double, 2>{w[0].get<double>(), w[1].get<double>()};
  }
  return s;
}

SliceImage draw_slice(const Volume& v, const ResolvedScene& r, const SliceRequest& s,
                      std::optional<std::array<int, 2>> size) {
  const glm::dvec3 want_up = r.scene.camera ? r.scene.camera->up : glm::dvec3(0, s.axis == 1 ? 0 : 1, s.axis == 1);
  const Frame f = s.axis >= 0 ? axis_frame(v, s, want_up) : plane_frame(v, s, want_up);
  SliceImage img;
  img.index = f.index;
  double pu = f.du, pv = f.dv, cu = f.u0, cv = f.v1;  // pixel size and the top-left corner
  if (size) {
    img.width = (*size)[0], img.height = (*size)[1];
    pu = pv = std::max((f.u1 - f.u0) / img.width, (f.v1 - f.v0) / img.height);
    cu = (f.u0 + f.u1) / 2 - pu * img.width / 2;
    cv = (f.v0 + f.v1) / 2 + pv * img.height / 2;
  } else {
    img.width = std::clamp(int(std::lround((f.u1 - f.u0) / f.du)), 1, kMaxImageSide);
    img.height = std::clamp(int(std::lround((f.v1 - f.v0) / f.dv)), 1, kMaxImageSide);
  }
  img.rgb.resize(size_t(img.width) * img.height * 3);
  for (int row = 0; row < img.height; ++row)
    for (int col = 0; col < img.width; ++col) {
      const glm::dvec3 p = f.p0 + f.right * (cu + (col + 0.5) * pu) + f.up * (cv - (row + 0.5) * pv);
      glm::dvec3 color = r.scene.background;
      int64_t ijk[3];
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        ijk[a] = int64_t(std::floor((p[a] - v.origin[a]) / v.spacing[a] + 0.5));  // the nearest voxel
        inside &= ijk[a] >= 0 && ijk[a] < v.dims()[a];
      }
      if (inside) {
        const double value = v.value(ijk[0], ijk[1], ijk[2]);
        if (s.window)
          color = glm::dvec3(std::clamp((value - (*s.window)[0]) / ((*s.window)[1] - (*s.window)[0]), 0.0, 1.0));
        else
          color = glm::dvec3(r.tf.eval(value));
      }
      uint8_t* out = &img.rgb[(size_t(row) * img.width + col) * 3];
      for (int c = 0; c < 3; ++c) out[c] = uint8_t(std::lround(std::clamp(color[c], 0.0, 1.0) * 255.0));
    }
  return img;
}

}  // namespace peakcast
