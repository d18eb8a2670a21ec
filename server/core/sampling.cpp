#include "core/sampling.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace peakcast {

SamplingPlan plan_sampling(const ResolvedScene& s, double step_scale) {
  SamplingPlan p;
  p.step = s.step * step_scale;
  if (s.scene.render.sampling != Sampling::Differential) return p;
  const ViewSetup view = setup_view(s.camera, glm::dvec3(0.0), s.scene.width, s.scene.height);
  // One pixel on the image plane per unit depth (perspective) or in world units (orthographic).
  p.pixel_du = 2.0 * view.half_w / s.scene.width;
  const double pixel_dv = 2.0 * view.half_h / s.scene.height;
  const double focus = s.camera.orthographic ? 1.0 : glm::length(s.camera.center - s.camera.eye);
  p.k = s.scene.render.s_k * step_scale * std::hypot(p.pixel_du, pixel_dv) * focus;
  p.min_step = kMinDifferentialStepFraction * s.min_spacing;
  if (s.camera.orthographic) {
    p.step = std::max(p.k, p.min_step);  // constant footprint: uniform at that step
    return p;
  }
  p.differential = true;
  return p;
}

double RayLattice::index_at(double t) const {
  const double d = std::max(0.0, t - t0);
  return 2.0 * d / (B + std::sqrt(B * B + 2.0 * A * d));
}

RayLattice ray_lattice(const SamplingPlan& plan, const ViewSetup& view, const Ray& r, double t_enter) {
  RayLattice l;
  l.t0 = t_enter;
  if (!plan.differential) {
    l.A = 0.0;
    l.B = plan.step;
    return l;
  }
  // Eq. 10 with d the ray's direction at depth 1 and u one pixel along the image plane's x.
  const glm::dvec3 d = r.d / glm::dot(r.d, view.forward);
  const glm::dvec3 u = view.right * plan.pixel_du;
  const double dd = glm::dot(d, d);
  const double dD_dx = glm::length(dd * u - glm::dot(d, u) * d) / (dd * std::sqrt(dd));
  const double a = plan.k * dD_dx, b = plan.k;
  const double s_enter = std::max(0.0, t_enter - r.t_eye);  // eye -> entry
  const double x_enter = 2.0 * s_enter / (b + std::sqrt(b * b + 2.0 * a * s_enter));
  l.A = a;
  l.B = std::max(b + a * x_enter, plan.min_step);
  return l;
}

std::vector<uint8_t> adaptive_multipliers(const MacrocellGrid& cells, double vol_std) {
  std::vector<uint8_t> m(cells.size(), uint8_t(kMaxAdaptiveMultiplier));
  for (size_t c = 0; c < cells.size(); ++c) {
    const double ratio = vol_std > 0.0 ? double(cells.stddev[c]) / vol_std : 0.0;
    const double M = ratio > 0.0 ? std::floor(2.0 / ratio + 1.0) : double(kMaxAdaptiveMultiplier);
    m[c] = uint8_t(std::clamp(M, 1.0, double(kMaxAdaptiveMultiplier)));
  }
  return m;
}

double volume_stddev(const Volume& v) {
  const auto& h = v.histogram;
  if (h.empty() || !(v.max_value > v.min_value)) return 0.0;
  const double w = (v.max_value - v.min_value) / double(h.size());
  double n = 0, sum = 0, sum2 = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    const double x = v.min_value + (double(i) + 0.5) * w, c = double(h[i]);
    n += c;
    sum += c * x;
    sum2 += c * x * x;
  }
  if (n <= 0) return 0.0;
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

}  // namespace peakcast
