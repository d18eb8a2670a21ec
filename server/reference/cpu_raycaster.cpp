#include "reference/cpu_raycaster.h"


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
#include "reference/ray_events.h"
#include "reference/shading.h"
#include "core/value_range.h"

namespace peakcast::reference {
namespace {

// What every pixel of a frame shares.
struct Frame {
  const Volume& v;
  const ResolvedScene& s;
  glm::dvec3 half;
  ViewSetup view;
  double lo, hi, min_spacing;
  Filter filter;
  bool shading;
  CenteredClip<glm::dvec3, double> clip;

  Frame(const Volume& vol, const ResolvedScene& sc)
      : v(vol), s(sc), filter(sc.scene.render.filter), shading(sc.scene.render.shading) {
    const glm::dvec3 center = (s.box_min + s.box_max) * 0.5;
    half = (s.box_max - s.box_min) * 0.5;
    view = setup_view(s.camera, center, s.scene.width, s.scene.height);
    const ValueRange range = table_range(v.min_value, v.max_value);
    lo = range.lo;
    hi = range.hi;
    min_spacing = std::min({v.spacing.x, v.spacing.y, v.spacing.z});
    clip = center_clip<glm::dvec3, double>(s.scene.render.clip, center);
  }
  // The ray's span through the box (t_box: its entry, where a volume-mapped ray texture is read)
  // cut by the clip; false when the ray misses the box (`missed`) or the clip keeps none of it.
  bool span(const Ray& r, double& t_box, double& t0, double& t1, bool& missed) const {
    missed = !intersect_box(r, half, t0, t1);
    t_box = t0;
    return !missed && clip_span(clip, r.o, r.d, t0, t1);
  }
  glm::dvec3 voxel(const Ray& r, double t) const { return (r.o + t * r.d + half) / v.spacing; }
  double field(const Ray& r, double t) const { return sample(v, voxel(r, t), filter); }
  glm::dvec3 lit(const glm::dvec3& rgb, const Ray& r, double t) const { return lit_with(rgb, grad(r, t), r); }
  glm::dvec3 grad(const Ray& r, double t) const { return gradient(v, voxel(r, t), filter); }
  // Shaded with a given gradient (data units per voxel): virtual samples interpolate it.
  glm::dvec3 lit_with(const glm::dvec3& rgb, const glm::dvec3& g, const Ray& r) const {
    return shading ? shade(rgb, g / (hi - lo), r.d, min_spacing) : rgb;
  }
};

struct Accum {
  glm::dvec3 rgb{0.0};
  double alpha = 0.0;
  // Where the ray is (t) and the value drawn there, set before each add: the probe's answer is
  // the first add that takes alpha past one half (probe.h).
  double at_t = 0.0, at_value = 0.0;
  double half_t = std::nan(""), half_value = 0.0;
  void add(const glm::dvec3& c, double a) {
    const double w = (1.0 - alpha) * a;
    if (alpha < 0.5 && alpha + w >= 0.5 && std::isnan(half_t)) half_t = at_t, half_value = at_value;
    rgb += w * c;
    alpha += w;
  }
};

// Catmull-Rom through p0..p3, between p1 (u = 0) and p2 (u = 1): twin of the shader's.
template <typename T>
T catmull_rom(const T& p0, const T& p1, const T& p2, const T& p3, double u) {
  return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u * u +
                (3.0 * p1 - p0 - 3.0 * p2 + p3) * u * u * u);
}

// Twin of shaders/peak_find.glsl solve_root.
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

template <typename PixelFn>
Image for_each_pixel(const Frame& fr, PixelFn fn) {
  const int w = fr.s.scene.width, h = fr.s.scene.height;
  Image img(w, h);
  parallel_for(size_t(h), [&](size_t row) {
    const int y = int(row);
    for (int x = 0; x < w; ++x) {
      const Ray r = make_ray(fr.view, x, y);
      double t_box, t0, t1, samples = -1.0;  // -1: the ray misses the box
      bool missed;
      Accum acc;
      if (fr.span(r, t_box, t0, t1, missed)) {
        samples = 0.0;
        fn(r, t_box, t0, t1, acc, samples, x, y);
      } else if (!missed) {
        samples = 0.0;  // clipped away
      }
      float* px = img.pixel(x, y);
      const glm::dvec3 out = acc.rgb + (1.0 - acc.alpha) * fr.s.scene.background;
      px[0] = float(out.x), px[1] = float(out.y), px[2] = float(out.z), px[3] = float(acc.alpha);
      img.samples[size_t(y) * w + x] = float(samples);
    }
  });
  return img;
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
  const PeakTable table = build_peak_table(peaks_on ? find_peaks(s.tf) : std::vector<Peak>{}, fr.lo, fr.hi,
                                           rs.peak_table_bins);
  const PreintegrationTable pre =
      preint ? build_preintegration(s.tf, fr.lo, fr.hi, dt, rs.preint_table_size, preint_method(rs)) : PreintegrationTable{};
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
    double t_prev = 0, f_prev = 0;
    bool first = true;
    // One sample (true or virtual) at t with value f, standing for `step`; g: its gradient (raw
    // units) when interpolated, else null and computed at t if shading needs it. True when the
    // ray is opaque. Twin of consume() in shaders/raycast_body.glsl.
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
    auto emit = [&](size_t a, bool has_prev, bool has_next2, double t_limit) {
      const double sub = w[a].step / (k_virtual + 1);
      if (consume(w[a].t, w[a].f, &w[a].g, sub)) return true;
      const size_t p0 = has_prev ? a - 1 : a, p3 = has_next2 ? a + 2 : a + 1;
      const double span = w[a + 1].t - w[a].t;
      for (int q = 1; q <= k_virtual; ++q) {
        const double u = double(q) / (k_virtual + 1);
        if (w[a].t + u * span > t_limit) break;
        const double f = catmull_rom(w[p0].f, w[a].f, w[a + 1].f, w[p3].f, u);
        const glm::dvec3 g = catmull_rom(w[p0].g, w[a].g, w[a + 1].g, w[p3].g, u);
        if (consume(w[a].t + u * span, f, &g, sub)) return true;
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
      if (!k_virtual) return consume(t, f, nullptr, step);
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
    if (!rs.adaptive) {
      for (int64_t i = 0; i <= last; ++i)
        if (visit(i, 1)) return;
      finish();
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
  });
}

}  // namespace

Image render_reference(const Volume& v, const ResolvedScene& s, const ReferenceOptions& opt) {
  const Frame fr(v, s);
  return run_reference(fr, opt, [&](const auto& pixel) { return for_each_pixel(fr, pixel); });
}

ProbeResult probe_reference(const Volume& v, const ResolvedScene& scene, int x, int y) {
  if (!v.has_voxels()) throw std::invalid_argument("probing needs the volume's voxels, which this process does not hold");
  if (x < 0 || y < 0 || x >= scene.scene.width || y >= scene.scene.height)
    throw std::invalid_argument("pixel [" + std::to_string(x) + ", " + std::to_string(y) + "] is outside the " +
                                std::to_string(scene.scene.width) + " x " + std::to_string(scene.scene.height) + " image");
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


ConvergedImage render_converged(const Volume& v, const ResolvedScene& s, OpticalModel model, double tolerance,
                                double min_step_voxels) {
  const Frame fr(v, s);
  std::vector<double> breakpoints, peak_values;
  for (const auto& p : s.tf.points) breakpoints.push_back(p.value);
  if (model == OpticalModel::Peaks)
    for (const auto& p : find_peaks(s.tf)) peak_values.push_back(p.value);
  // The ray splits do not depend on the step: find them once per pixel.
  const int w = s.scene.width, h = s.scene.height;
  std::vector<RaySplit> splits(size_t(w) * h);
  std::vector<double> enter(splits.size(), 0.0);
  std::vector<char> hit(splits.size(), 0);
  parallel_for(size_t(h), [&](size_t row) {
    for (int x = 0; x < w; ++x) {
      const Ray r = make_ray(fr.view, x, int(row));
      double t_box, t0, t1;
      bool missed;
      const size_t k = row * size_t(w) + size_t(x);
      if (fr.span(r, t_box, t0, t1, missed)) {
        hit[k] = 1;
        splits[k] = split_ray(v, fr.filter, r, fr.half, t0, t1, breakpoints, peak_values);
      }
    }
  });
  auto render_at = [&](double step) {
    // Misses keep the background (for_each_pixel with nothing to integrate), hits are filled below.
    Image img = for_each_pixel(fr, [](const Ray&, double, double, double, Accum&, double&, int, int) {});
    parallel_for(size_t(h), [&](size_t row) {
      for (int x = 0; x < w; ++x) {
        const size_t k = row * size_t(w) + size_t(x);
        if (!hit[k]) continue;
        const Ray r = make_ray(fr.view, x, int(row));
        const RaySplit& sp = splits[k];
        Accum acc;
        double samples = 0;
        size_t next_peak = 0;
        for (size_t c = 0; c + 1 < sp.cuts.size(); ++c) {
          const double a = sp.cuts[c], b = sp.cuts[c + 1];
          while (next_peak < sp.peaks.size() && sp.peaks[next_peak].t <= a) {  // surfaces at this cut
            const double pv = sp.peaks[next_peak].value;
            const glm::dvec4 col = s.tf.eval(pv);
            acc.add(fr.lit(glm::dvec3(col), r, sp.peaks[next_peak].t), col.a);
            ++next_peak;
          }
          if (b <= a) continue;
          // Midpoint steps of at most `step`, and small enough that opacity changes by at most
          // `da` per step: inside a Dirac-like tent the field lingers where the TF is steep.
          const double da = 0.02 * step / s.step;
          const double a0 = s.tf.eval(fr.field(r, a)).a, a1 = s.tf.eval(fr.field(r, b)).a;
          const int pieces = std::min(1 << 16, std::max({1, int(std::ceil((b - a) / step)), int(std::ceil(std::abs(a1 - a0) / da))}));
          const double hstep = (b - a) / pieces;
          for (int q = 0; q < pieces; ++q) {
            const double t = a + (q + 0.5) * hstep;
            const glm::dvec4 col = s.tf.eval(fr.field(r, t));
            samples += 1;
            if (col.a > 0) acc.add(fr.lit(glm::dvec3(col), r, t), correct_opacity(col.a, hstep, s.tf.opacity_unit));
          }
        }
        while (next_peak < sp.peaks.size()) {
          const glm::dvec4 col = s.tf.eval(sp.peaks[next_peak].value);
          acc.add(fr.lit(glm::dvec3(col), r, sp.peaks[next_peak].t), col.a);
          ++next_peak;
        }
        float* px = img.pixel(x, int(row));
        const glm::dvec3 out = acc.rgb + (1.0 - acc.alpha) * s.scene.background;
        px[0] = float(out.x), px[1] = float(out.y), px[2] = float(out.z), px[3] = float(acc.alpha);
        img.samples[k] = float(samples);
      }
    });
    return img;
  };
  ConvergedImage out;
  out.step = s.step;
  out.image = render_at(out.step);
  while (out.step > min_step_voxels * fr.min_spacing) {
    Image finer = render_at(out.step * 0.5);
    double change = 0;
    for (size_t i = 0; i < finer.rgba.size(); ++i)
      if (i % 4 != 3) change = std::max(change, double(std::abs(finer.rgba[i] - out.image.rgba[i])));
    out.image = std::move(finer);
    out.step *= 0.5;
    out.last_change = change;
    if (std::getenv("PEAKCAST_DEBUG_CONVERGENCE")) std::fprintf(stderr, "step %g change %g\n", out.step, change);
    out.refinements++;
    if (change < tolerance) {
      out.converged = true;
      break;
    }
  }
  return out;
}

}  // namespace peakcast::reference
