// Camera and ray generation shared by the GL ray caster and the CPU reference (docs/scenes.md).
// Rays are expressed in the box-centred frame, starting near the box rather than at the eye,
// so that float precision holds for a camera far away (see shaders/ray/ray_setup.glsl).
#pragma once

#include <string>

#include <glm/vec3.hpp>

namespace peakcast {

struct Camera {
  glm::dvec3 eye{0, 0, 1}, center{0, 0, 0}, up{0, 1, 0};
  double fov_y = 30.0;  // degrees, vertical
  bool orthographic = false;
  double height = 1.0;  // world units, orthographic only
  std::string to_string() const;
};

// The first view of a box: VTK's ResetCamera (looking down -z at the box centre from the
// distance where the bounding sphere fills the vertical view angle), then turned as VTK's
// Azimuth (about the view up, +y) and Elevation (towards the view up) would turn it, by
// `azimuth` and `elevation` degrees: a three-quarter view unless both are 0.
Camera default_camera(const glm::dvec3& box_min, const glm::dvec3& box_max, double fov_y = 30.0, double azimuth = 30.0,
                      double elevation = 20.0);

// Throws std::invalid_argument for eye == center, up parallel to the view, bad fov or height.
void validate_camera(const Camera& c);

struct ViewSetup {
  glm::dvec3 p0;                  // view-axis point nearest the box centre, relative to the box centre
  glm::dvec3 right, up, forward;  // orthonormal; up orthogonalised against forward
  double half_w = 0, half_h = 0;  // image-plane half size per unit depth (ortho: world units)
  double dist = 0;                // eye -> p0 along forward
  bool orthographic = false;
  int width = 1, height = 1;
};

ViewSetup setup_view(const Camera& c, const glm::dvec3& box_center, int width, int height);

struct Ray {
  glm::dvec3 o, d;   // box-centred origin, unit direction
  double t_eye = 0;  // rays start at max(t_eye, box entry)
};

// Ray through the centre of pixel (px, py), row 0 at the top.
Ray make_ray(const ViewSetup& v, int px, int py);

// Slab test against [-half, half]; returns false when the ray misses.
bool intersect_box(const Ray& r, const glm::dvec3& half, double& t_enter, double& t_exit);

}  // namespace peakcast
