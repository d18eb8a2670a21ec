#include "core/camera.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <glm/geometric.hpp>

namespace peakcast {

std::string Camera::to_string() const {
  std::ostringstream s;
  s << "Camera{eye (" << eye.x << "," << eye.y << "," << eye.z << ") center (" << center.x << "," << center.y << ","
    << center.z << ") up (" << up.x << "," << up.y << "," << up.z << ") "
    << (orthographic ? "ortho height " + std::to_string(height) : "fov_y " + std::to_string(fov_y)) << "}";
  return s.str();
}

Camera default_camera(const glm::dvec3& lo, const glm::dvec3& hi, double fov_y, double azimuth, double elevation) {
  Camera c;
  c.fov_y = fov_y;
  c.center = (lo + hi) * 0.5;
  const double radius = glm::length(hi - lo) * 0.5;  // > 0: a volume has two voxels or more on each axis
  const double distance = radius / std::sin(fov_y * M_PI / 360.0);
  // From +z, azimuth turns right-handed about +y, elevation lifts towards +y.
  const double az = azimuth * M_PI / 180.0, el = elevation * M_PI / 180.0;
  c.eye = c.center + distance * glm::dvec3(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  c.up = {0, 1, 0};
  c.height = 2.0 * radius;
  return c;
}

void validate_camera(const Camera& c) {
  auto finite = [](const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  if (!finite(c.eye) || !finite(c.center) || !finite(c.up)) throw std::invalid_argument("camera: non-finite vector");
  const glm::dvec3 view = c.center - c.eye;
  const double len = glm::length(view);
  if (!(len > 0)) throw std::invalid_argument("camera: eye equals center");
  if (!(glm::length(c.up) > 0)) throw std::invalid_argument("camera.up: zero vector");
  if (glm::length(glm::cross(view / len, glm::normalize(c.up))) < 1e-6)
    throw std::invalid_argument("camera.up: parallel to the view direction (eye -> center)");
  if (!c.orthographic && !(c.fov_y > 0 && c.fov_y < 180))
    throw std::invalid_argument("camera.fov_y: must be in (0, 180) degrees");
  if (c.orthographic && !(c.height > 0 && std::isfinite(c.height)))
    throw std::invalid_argument("camera.height: must be > 0");
}

ViewSetup setup_view(const Camera& c, const glm::dvec3& box_center, int width, int height) {
  ViewSetup v;
  v.width = width;
  v.height = height;
  v.orthographic = c.orthographic;
  v.forward = glm::normalize(c.center - c.eye);
  v.right = glm::normalize(glm::cross(v.forward, c.up));
  v.up = glm::cross(v.right, v.forward);
  const double aspect = double(width) / double(height);
  const double half = c.orthographic ? c.height * 0.5 : std::tan(c.fov_y * M_PI / 360.0);
  v.half_h = half;
  v.half_w = half * aspect;
  const glm::dvec3 eye_rel = c.eye - box_center;
  v.dist = glm::dot(-eye_rel, v.forward);
  v.p0 = eye_rel + v.dist * v.forward;
  return v;
}

Ray make_ray(const ViewSetup& v, int px, int py) {
  const double nx = (px + 0.5) / v.width * 2.0 - 1.0;
  const double ny = 1.0 - (py + 0.5) / v.height * 2.0;
  const glm::dvec3 lateral = nx * v.half_w * v.right + ny * v.half_h * v.up;
  Ray r;
  if (v.orthographic) {
    r.o = v.p0 + lateral;
    r.d = v.forward;
    r.t_eye = -v.dist;
  } else {
    const glm::dvec3 d = v.forward + lateral;
    const double len = glm::length(d);
    r.o = v.p0 + v.dist * lateral;
    r.d = d / len;
    r.t_eye = -v.dist * len;
  }
  return r;
}

bool intersect_box(const Ray& r, const glm::dvec3& half, double& t_enter, double& t_exit) {
  double lo = -1e300, hi = 1e300;
  for (int a = 0; a < 3; ++a) {
    const double d = std::abs(r.d[a]) < 1e-20 ? 1e-20 : r.d[a];
    double t0 = (-half[a] - r.o[a]) / d, t1 = (half[a] - r.o[a]) / d;
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  t_enter = std::max(lo, r.t_eye);
  t_exit = hi;
  return t_enter <= t_exit;
}

}  // namespace peakcast
