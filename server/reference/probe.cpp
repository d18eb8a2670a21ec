// The viewer's probe and the depth image: the reference ray of the scene's method, and its first
// visible surface or where its accumulated opacity first passes one half (reference_renderer.h).
#include <cmath>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "reference/ray_frame.h"
#include "reference/ray_math.h"
#include "reference/reference_renderer.h"

namespace peakcast::reference {
namespace {

using namespace detail;

ProbeResult probe_ray(const Frame& fr, const PixelRay& pixel, int x, int y, ProbePick pick) {
  ProbeResult out;
  const Ray r = make_ray(fr.view, x, y);
  double t_box, t0, t1, samples = 0.0;
  bool missed;
  Accum acc;
  if (pick == ProbePick::Surface) {
    acc.pick_tf = &fr.s.tf;
    acc.pick_opacity = kPickOpacity;
  }
  if (!fr.span(r, t_box, t0, t1, missed)) return out;
  pixel(r, t_box, t0, t1, acc, samples, x, y);
  out.opacity = acc.alpha;
  const bool surface = !std::isnan(acc.first_t);
  const double t = surface ? acc.first_t : acc.half_t;
  if (std::isnan(t)) return out;
  out.hit = true;
  out.pick = surface ? ProbePick::Surface : ProbePick::Half;
  out.position = r.o + t * r.d + (fr.s.box_min + fr.s.box_max) * 0.5;
  out.value = surface ? acc.first_value : acc.half_value;
  out.distance = t - r.t_eye;
  return out;
}

// Adaptive sampling would build the whole volume's macrocells for one ray: the scene's uniform
// lattice instead (the half-opacity point moves by less than a step).
ResolvedScene uniform_lattice(const ResolvedScene& scene) {
  ResolvedScene s = scene;
  s.scene.render.adaptive = false;
  return s;
}

void need_voxels(const Volume& v) {
  if (!v.has_voxels())
    throw std::invalid_argument("probing needs the volume's voxels, which this process does not hold");
}

}  // namespace

const char* to_string(ProbePick p) { return p == ProbePick::Surface ? "surface" : "half"; }

ProbePick parse_probe_pick(const std::string& name) {
  if (name == "surface") return ProbePick::Surface;
  if (name == "half") return ProbePick::Half;
  throw std::invalid_argument("pick: '" + name + "' is not one of surface, half");
}

ProbeResult probe_reference(const Volume& v, const ResolvedScene& scene, int x, int y, ProbePick pick) {
  need_voxels(v);
  if (x < 0 || y < 0 || x >= scene.scene.width || y >= scene.scene.height)
    throw std::invalid_argument("pixel [" + std::to_string(x) + ", " + std::to_string(y) + "] is outside the " +
                                std::to_string(scene.scene.width) + " x " + std::to_string(scene.scene.height) +
                                " image");
  const ResolvedScene s = uniform_lattice(scene);
  const Frame fr(v, s);
  ProbeResult out;
  with_reference_ray(fr, [&](const PixelRay& pixel) { out = probe_ray(fr, pixel, x, y, pick); });
  return out;
}

std::vector<float> depth_reference(const Volume& v, const ResolvedScene& scene) {
  need_voxels(v);
  const ResolvedScene s = uniform_lattice(scene);
  const Frame fr(v, s);
  const int w = s.scene.width, h = s.scene.height;
  std::vector<float> depth(size_t(w) * size_t(h));
  with_reference_ray(fr, [&](const PixelRay& pixel) {
    parallel_for(size_t(h), [&](size_t row) {
      for (int x = 0; x < w; ++x) {
        const ProbeResult p = probe_ray(fr, pixel, x, int(row), ProbePick::Half);
        depth[row * size_t(w) + size_t(x)] = p.hit ? float(p.distance) : std::nanf("");
      }
    });
  });
  return depth;
}

}  // namespace peakcast::reference
