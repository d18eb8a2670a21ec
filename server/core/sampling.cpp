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
  p.footprint = std::hypot(p.pixel_du, pixel_dv) * focus;
  const double at_focus = s.scene.render.s_k * step_scale * p.footprint;  // the step wanted there
  p.min_step = kMinDifferentialStepFraction * s.min_spacing;
  if (s.camera.orthographic) {
    p.k = at_focus;
    p.step = std::max(p.k, p.min_step);  // constant footprint: uniform at that step
    return p;
  }
  // k^2 + 2 k g = at_focus^2 (the central ray: |dD/dx| = pixel_du), in the form without
  // cancellation when g >> at_focus.
  const double g = p.pixel_du * focus;
  p.k = at_focus * at_focus / (g + std::sqrt(g * g + at_focus * at_focus));
  p.differential = true;
  return p;
}

double longest_step(const SamplingPlan& plan, const ResolvedScene& s) {
  if (!plan.differential) return plan.step;
  double far = 0.0;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner(c & 1 ? s.box_max.x : s.box_min.x, c & 2 ? s.box_max.y : s.box_min.y,
                            c & 4 ? s.box_max.z : s.box_min.z);
    far = std::max(far, glm::length(corner - s.camera.eye));
  }
  // a = k |dD/dx| <= k * pixel_du (the footprint grows no faster than on the axis); the step
  // from index j to j + 1 is the one at t(j) plus a/2.
  const double a = plan.k * plan.pixel_du;
  return plan.min_step + std::sqrt(plan.k * plan.k + 2.0 * a * far) + 0.5 * a;
}

int virtual_sample_ring(const SamplingPlan& plan, const ResolvedScene& s, int cell_edge) {
  const double mult = s.scene.render.adaptive ? kMaxAdaptiveMultiplier : 1.0;
  const double reach = 2.0 * longest_step(plan, s) * mult / s.min_spacing;  // voxels, at most
  const double ring = std::ceil(reach / std::max(cell_edge, 1));
  return std::isfinite(ring) && ring <= kMaxVirtualSampleRing ? int(ring) : -1;
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

std::vector<CellCrossing> cells_along(const MacrocellGrid& g, const Ray& r, double t0, double t1,
                                      const glm::dvec3& spacing, const glm::dvec3& half) {
  std::vector<CellCrossing> out;
  const double edge = g.cell;
  const glm::dvec3 x0 = (r.o + t0 * r.d + half) / spacing;
  const glm::dvec3 dv = r.d / spacing;
  int64_t cell[3], step[3];
  double t_max[3], t_delta[3];
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp<int64_t>(int64_t(std::floor(x0[a] / edge)), 0, g.grid[size_t(a)] - 1);
    step[a] = dv[a] > 0 ? 1 : dv[a] < 0 ? -1 : 0;
    if (std::abs(dv[a]) < 1e-20) {
      t_max[a] = t_delta[a] = 3.0e38;
    } else {
      const double face = (double(cell[a]) + (dv[a] > 0 ? 1.0 : 0.0)) * edge;
      t_max[a] = t0 + (face - x0[a]) / dv[a];
      t_delta[a] = edge / std::abs(dv[a]);
    }
  }
  double t_in = t0;
  const int64_t guard = 4 * (g.grid[0] + g.grid[1] + g.grid[2]) + 4;
  for (int64_t k = 0; k < guard; ++k) {
    const double t_out = std::min({t_max[0], t_max[1], t_max[2]});
    bool outside = false;
    int64_t c[3];
    for (int a = 0; a < 3; ++a) {
      outside = outside || cell[a] < 0 || cell[a] >= g.grid[size_t(a)];
      c[a] = std::clamp<int64_t>(cell[a], 0, g.grid[size_t(a)] - 1);
    }
    const bool final_cell = t_out >= t1 || outside;
    out.push_back({g.index(c[0], c[1], c[2]), t_in, final_cell ? t1 : t_out});
    if (final_cell) break;
    for (int a = 0; a < 3; ++a)
      if (t_max[a] <= t_out) {
        cell[a] += step[a];
        t_max[a] += t_delta[a];
      }
    t_in = t_out;
  }
  return out;
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
