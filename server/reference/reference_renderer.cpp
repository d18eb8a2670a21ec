#include "reference/reference_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>

#include "core/parallel.h"
#include "core/peaks.h"
#include "core/preintegration.h"
#include "core/ray_texture_mapping.h"
#include "core/sampling.h"
#include "reference/field.h"
#include "reference/shading.h"
#include "core/value_range.h"

#include "reference/ray_frame.h"

namespace peakcast::reference {
namespace {

using namespace detail;

// Catmull-Rom through p0..p3, between p1 (u = 0) and p2 (u = 1): twin of the shader's.
template <typename T>
T catmull_rom(const T& p0, const T& p1, const T& p2, const T& p3, double u) {
  return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u * u +
                (3.0 * p1 - p0 - 3.0 * p2 + p3) * u * u * u);
}

// The backends' is solve_root in shaders/ray/peaks.glsl.
double solve_root(const Frame& fr, const Ray& r, double t0, double f0, double t1, double f1, double v, int iters,
                  double& evaluations) {
  double ta = t0, tb = t1, ga = f0 - v, gb = f1 - v;
  for (int k = 0; k < iters; ++k) {
    if (gb == ga) break;
    const double t = std::clamp(ta - ga * (tb - ta) / (gb - ga), std::min(ta, tb), std::max(ta, tb));
    const double g = fr.field(r, t) - v;
    evaluations += 1;
    if ((g >= 0) == (ga >= 0)) {
      ta = t;
      ga = g;
    } else {
      tb = t;
      gb = g;
    }
  }
  return gb == ga ? 0.5 * (ta + tb) : std::clamp(ta - ga * (tb - ta) / (gb - ga), std::min(ta, tb), std::max(ta, tb));
}

// The set-up of a reference frame, then `body(pixel)` with the per-ray function
// pixel(ray, t0, t1, acc, samples, x, y): the whole image, or one pixel for a probe.
template <typename Body>
auto run_reference(const Frame& fr, const ReferenceOptions& opt, Body body) {
  const Volume& v = fr.v;
  const ResolvedScene& s = fr.s;
  const RenderSettings& rs = s.scene.render;
  SamplingPlan plan = plan_sampling(s, opt.step_scale);
  if (opt.step > 0 && !plan.differential) plan.step = opt.step;
  const double dt = plan.step;  // the uniform step: the preintegration table's segment length
  const double stop_default = opt.early_termination ? rs.early_termination : 2.0;
  const bool peaks_on = rs.classification == Classification::Peaks && rs.peak_mode != PeakMode::DvrOnly;
  const bool preint = rs.classification == Classification::Preint;
  const bool dvr_on = !(peaks_on && rs.peak_mode == PeakMode::PeaksOnly);
  // Steps that differ from the table's: preintegrated segments corrected for their length.
  const bool varying_steps = plan.differential || rs.adaptive || rs.virtual_samples;
  const PeakTable table =
      build_peak_table(peaks_on ? find_peaks(s.tf) : std::vector<Peak>{}, fr.lo, fr.hi, rs.peak_table_bins);
  const PreintegrationTable pre =
      preint ? build_preintegration(s.tf, fr.lo, fr.hi, dt, rs.preint_table_size, preint_method(rs))
             : PreintegrationTable{};
  MacrocellGrid cells;
  std::vector<uint8_t> multiplier;
  if (rs.adaptive) {
    cells = build_macrocells(v, 0, rs.filter == Filter::Tricubic ? FilterSupport::Tricubic : FilterSupport::Trilinear);
    multiplier = adaptive_multipliers(cells, volume_stddev(v));
  }
  const std::optional<RayTexture> ray_texture =
      s.ray_texture ? std::optional<RayTexture>(build_ray_texture(*s.ray_texture, rs.early_termination)) : std::nullopt;
  return body([&](const Ray& r, double t_box, double t0, double t1, Accum& acc, double& samples, int x, int y) {
    // The ray texture's controls (twin of shaders/ray_texture.glsl): step multiplier,
    // termination, DVR/peak blend.
    double step_mult = 1.0, stop = stop_default, dvr_weight = 1.0, peak_weight = 1.0;
    if (ray_texture) {
      const glm::dvec2 uv = s.ray_texture->mapping == RayTextureMapping::View
                                ? view_uv(x, y, s.scene.width, s.scene.height)
                                : volume_uv(r.o + t_box * r.d, fr.half);
      const auto c = sample_ray_texture(*ray_texture, uv);
      step_mult = c[0];
      if (opt.early_termination) stop = c[1];
      dvr_weight = 1.0 - std::max(c[2], 0.0);
      peak_weight = 1.0 + std::min(c[2], 0.0);
    }
    RayLattice lattice = ray_lattice(plan, fr.view, r, t0);
    lattice.A *= step_mult;
    lattice.B *= step_mult;
    const int64_t last = std::min<int64_t>(int64_t(std::floor(lattice.index_at(t1))), kMaxSamplesPerRay - 1);
    // The chord each sample stands for (midpoint rule): the lattice's [i - 1/2, i + m - 1/2], cut
    // at the ray's entry and exit, so the first sample stands for half a step and the last one
    // for half a step before it and the rest up to the exit (the backends' is
    // chord_at_ends in shaders/ray/lattice.glsl). Virtual samples: the same on the sub-lattice (emit).
    const double head = -(lattice.t(0.5) - lattice.t(0.0));
    const double tail = std::min(t1 - lattice.t(double(last)), lattice.step(double(last), 1)) -
                        (lattice.t(double(last) + 0.5) - lattice.t(double(last)));
    auto chord = [&](int64_t i, int m) {
      double w = lattice.step(double(i), m);
      if (i == 0) w += head;
      if (i + m > last) w += tail;
      return w;
    };
    int64_t visited_end = -1;  // the last visit's i + m (preintegration closes the ray from it)
    double t_prev = 0, f_prev = 0;
    bool first = true;
    // One sample (true or virtual) at t with value f, standing for `step`; g: its gradient (raw
    // units) when interpolated, else null and computed at t if shading needs it. True when the
    // ray is opaque. The backends' is consume() in shaders/ray/consume.glsl.
    auto consume = [&](double t, double f, const glm::dvec3* g, double step) {
      auto lit = [&](const glm::dvec3& rgb) { return fr.shading ? fr.lit_with(rgb, g ? *g : fr.grad(r, t), r) : rgb; };
      bool peak_hit = false;
      if (peaks_on && !first) {
        for (double pv : peaks_crossed(table, f_prev, f, rs.max_peaks)) {
          const double tr = solve_root(fr, r, t_prev, f_prev, t, f, pv, rs.secant_iterations, samples);
          const glm::dvec4 c = s.tf.eval(pv);
          acc.at_t = tr, acc.at_value = pv;
          acc.add(fr.lit(glm::dvec3(c), r, tr), c.a * peak_weight);
          peak_hit = true;
          if (acc.alpha >= stop) break;
        }
      }
      acc.at_t = t, acc.at_value = f;
      if (preint) {
        if (!first) {
          glm::dvec4 c = lookup_preintegration(pre, f_prev, f);
          if (varying_steps && c.a > 0) {
            const double a = correct_opacity(c.a, t - t_prev, dt);
            c = glm::dvec4(glm::dvec3(c) * (a / c.a), a);
          }
          if (c.a > 0) acc.add(lit(glm::dvec3(c) / c.a), c.a * dvr_weight);
        }
      } else if (dvr_on && !(peak_hit && rs.peak_mode == PeakMode::Xor)) {
        const glm::dvec4 c = s.tf.eval(f);
        if (c.a > 0) acc.add(lit(glm::dvec3(c)), correct_opacity(c.a, step, s.tf.opacity_unit) * dvr_weight);
      }
      t_prev = t;
      f_prev = f;
      first = false;
      return acc.alpha >= stop;
    };
    // Virtual samples (Lee §3.1, §4): the same window of four true samples as the shader's.
    const int k_virtual = rs.virtual_samples;
    struct True {
      double t, f, step;
      glm::dvec3 g;
    };
    std::vector<True> w;  // waiting true samples, at most 4
    // The sub-samples' chords as the true samples' (chord()), on the sub-lattice: the ray's first
    // sample stands for half a sub-step, and the last before the exit (t_limit, the ray's last
    // segment) for half a sub-step before it and the rest up to the exit.
    auto emit = [&](size_t a, bool has_prev, bool has_next2, double t_limit) {
      const double sub = w[a].step / (k_virtual + 1);
      const size_t p0 = has_prev ? a - 1 : a, p3 = has_next2 ? a + 2 : a + 1;
      const double span = w[a + 1].t - w[a].t;
      for (int q = 0; q <= k_virtual; ++q) {
        const double u = double(q) / (k_virtual + 1);
        const double t = w[a].t + u * span;
        if (q > 0 && t > t_limit) break;
        double weight = sub;
        if (q == 0 && w[a].t == lattice.t(0.0)) weight -= 0.5 * sub;
        if (std::isfinite(t_limit) && (q == k_virtual || w[a].t + double(q + 1) / (k_virtual + 1) * span > t_limit))
          weight += (t_limit - t) - 0.5 * sub;
        if (q == 0) {
          if (consume(w[a].t, w[a].f, &w[a].g, weight)) return true;
          continue;
        }
        const double f = catmull_rom(w[p0].f, w[a].f, w[a + 1].f, w[p3].f, u);
        const glm::dvec3 g = catmull_rom(w[p0].g, w[a].g, w[a + 1].g, w[p3].g, u);
        if (consume(t, f, &g, weight)) return true;
      }
      return false;
    };
    auto flush = [&]() {
      bool done = acc.alpha >= stop;
      const size_t n = w.size();
      if (!done && n >= 2) done = emit(n - 2, n >= 3, false, HUGE_VAL);
      if (!done && n >= 1) done = consume(w[n - 1].t, w[n - 1].f, &w[n - 1].g, w[n - 1].step);
      w.clear();
      return done;
    };
    // Visits index i, standing for the m lattice steps after it; true when the ray is opaque.
    auto visit = [&](int64_t i, int m) {
      const double t = lattice.t(double(i));
      const double step = lattice.step(double(i), m);
      const double f = fr.field(r, t);
      samples += 1;
      visited_end = i + m;
      if (!k_virtual) return consume(t, f, nullptr, chord(i, m));
      if (w.size() == 4) w.erase(w.begin());
      w.push_back({t, f, step, fr.shading ? fr.grad(r, t) : glm::dvec3(0.0)});
      if (w.size() == 3) return emit(0, false, true, HUGE_VAL);
      if (w.size() == 4) return emit(1, true, true, HUGE_VAL);
      return false;
    };
    // The ray's end (twin of vs_finish): one more true sample past the exit closes the spline;
    // the virtual samples up to the exit go out.
    auto finish = [&]() {
      if (!k_virtual) return;
      if (acc.alpha >= stop || w.empty()) return;
      if (w.back().t != lattice.t(double(last))) {
        flush();
        return;
      }
      const double t = lattice.t(double(last + 1));
      samples += 1;
      const glm::dvec3 g = fr.shading ? fr.grad(r, t) : glm::dvec3(0.0);
      if (w.size() == 4) w.erase(w.begin());
      w.push_back({t, fr.field(r, t), lattice.step(double(last + 1), 1), g});
      if (w.size() == 3 && emit(0, false, true, HUGE_VAL)) return;
      if (w.size() == 4 && emit(1, true, true, HUGE_VAL)) return;
      emit(w.size() - 2, w.size() >= 3, false, t1);
      w.clear();
    };
    // Preintegration's last segment, from the last lattice point to the exit (the table's
    // segments cover the chord between samples; the rest of the ray is this one).
    auto close = [&]() {
      if (!preint || k_virtual || first || visited_end != last + 1 || acc.alpha >= stop) return;
      const double f = fr.field(r, t1);
      samples += 1;
      glm::dvec4 c = lookup_preintegration(pre, f_prev, f);
      if (!(c.a > 0)) return;
      const double a = correct_opacity(c.a, t1 - t_prev, dt);
      acc.at_t = t1, acc.at_value = f;
      acc.add(fr.lit(glm::dvec3(c) / c.a, r, t1), a * dvr_weight);
    };
    if (!rs.adaptive) {
      for (int64_t i = 0; i <= last; ++i)
        if (visit(i, 1)) return;
      finish();
      close();
      return;
    }
    // Adaptive: the cells in ray order (the GPU's traversal), every m-th index from each cell's
    // first, the last one standing for the steps up to the cell's end.
    int64_t next = 0;
    const auto crossings = cells_along(cells, r, t0, t1, v.spacing, fr.half);
    for (size_t k = 0; k < crossings.size() && next <= last; ++k) {
      const CellCrossing& c = crossings[k];
      const bool final_cell = k + 1 == crossings.size();
      const int64_t first_i = int64_t(std::ceil(lattice.index_at(c.t_in)));
      const int64_t end = final_cell ? last : std::min(last, int64_t(std::ceil(lattice.index_at(c.t_out))) - 1);
      const int m = multiplier[c.cell];
      for (int64_t i = std::max(next, first_i); i <= end; i += m)
        if (visit(i, int(std::min<int64_t>(m, end + 1 - i)))) return;
      next = std::max(next, end + 1);
    }
    finish();
    close();
  });
}

}  // namespace

Image render_reference(const Volume& v, const ResolvedScene& s, const ReferenceOptions& opt) {
  const Frame fr(v, s);
  return run_reference(fr, opt, [&](const auto& pixel) { return for_each_pixel(fr, pixel); });
}

ProbeResult probe_reference(const Volume& v, const ResolvedScene& scene, int x, int y) {
  if (!v.has_voxels())
    throw std::invalid_argument("probing needs the volume's voxels, which this process does not hold");
  if (x < 0 || y < 0 || x >= scene.scene.width || y >= scene.scene.height)
    throw std::invalid_argument("pixel [" + std::to_string(x) + ", " + std::to_string(y) + "] is outside the " +
                                std::to_string(scene.scene.width) + " x " + std::to_string(scene.scene.height) +
                                " image");
  // Adaptive sampling would build the whole volume's macrocells for one ray: the scene's
  // uniform lattice instead (the half-opacity point moves by less than a step).
  ResolvedScene s = scene;
  s.scene.render.adaptive = false;
  const Frame fr(v, s);
  return run_reference(fr, ReferenceOptions{}, [&](const auto& pixel) {
    ProbeResult out;
    const Ray r = make_ray(fr.view, x, y);
    double t_box, t0, t1, samples = 0.0;
    bool missed;
    Accum acc;
    if (!fr.span(r, t_box, t0, t1, missed)) return out;
    pixel(r, t_box, t0, t1, acc, samples, x, y);
    out.opacity = acc.alpha;
    if (std::isnan(acc.half_t)) return out;
    out.hit = true;
    out.position = r.o + acc.half_t * r.d + (s.box_min + s.box_max) * 0.5;
    out.value = acc.half_value;
    out.distance = acc.half_t - r.t_eye;
    return out;
  });
}

}  // namespace peakcast::reference
