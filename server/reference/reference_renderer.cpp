#include "reference/reference_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <vector>

#include "core/parallel.h"
#include "core/peaks.h"
#include "core/preintegration.h"
#include "core/ray_texture_mapping.h"
#include "core/sampling.h"
#include "core/value_range.h"
#include "reference/field.h"
#include "reference/shading.h"

#include "reference/ray_frame.h"
#include "reference/ray_math.h"

namespace peakcast::reference {
namespace {

using namespace detail;

// What every ray of a reference frame reads: the sampling plan, the
// classification's switches and its tables, the macrocells' multipliers
// (adaptive) and the ray texture.
struct FrameTables {
  SamplingPlan plan;
  double dt = 0;      // the uniform step: the preintegration table's segment length
  double stop = 2.0;  // early termination (2: none)
  bool peaks_on = false, preint = false, dvr_on = true;
  Classification projection = Classification::Post;  // mip, minip or average; else post (none)
  bool varying_steps = false;                        // steps that differ from the table's:
                                                     // preintegrated segments corrected
  PeakTable table;
  PreintegrationTable pre;
  MacrocellGrid cells;
  std::vector<uint8_t> multiplier;
  std::optional<RayTexture> ray_texture;
};

FrameTables make_tables(const Frame& fr, const ReferenceOptions& opt) {
  const ResolvedScene& s = fr.s;
  const RenderSettings& rs = s.scene.render;
  FrameTables t;
  t.plan = plan_sampling(s, opt.step_scale);
  if (opt.step > 0 && !t.plan.differential) t.plan.step = opt.step;
  t.dt = t.plan.step;
  t.stop = opt.early_termination ? rs.early_termination : 2.0;
  t.peaks_on = rs.classification == Classification::Peaks && rs.peak_mode != PeakMode::DvrOnly;
  t.preint = rs.classification == Classification::Preint;
  t.dvr_on = !(t.peaks_on && rs.peak_mode == PeakMode::PeaksOnly);
  if (is_projection(rs.classification)) t.projection = rs.classification;
  t.varying_steps = t.plan.differential || rs.adaptive || rs.virtual_samples;
  t.table = build_peak_table(t.peaks_on ? find_peaks(s.tf) : std::vector<Peak>{}, fr.lo, fr.hi, rs.peak_table_bins);
  if (t.preint) t.pre = build_preintegration(s.tf, fr.lo, fr.hi, t.dt, rs.preint_table_size, preint_method(rs));
  if (rs.adaptive) {
    const FilterSupport support = rs.filter == Filter::Tricubic ? FilterSupport::Tricubic : FilterSupport::Trilinear;
    t.cells = build_macrocells(fr.v, 0, support);
    t.multiplier = adaptive_multipliers(t.cells, volume_stddev(fr.v));
  }
  if (s.ray_texture) t.ray_texture = build_ray_texture(*s.ray_texture, rs.early_termination);
  return t;
}

// One reference ray from its box span to its end: the ray texture's controls,
// the lattice and each sample's chord, the samples (true and virtual)
// classified and composited into `acc`. The backends' twins are named at each
// step (shaders/ray/).
class RefRay {
 public:
  RefRay(const Frame& fr, const FrameTables& t, const ReferenceOptions& opt, const Ray& r, double t_box, double t0,
         double t1, Accum& acc, double& samples, int x, int y)
      : fr_(fr), t_(t), rs_(fr.s.scene.render), r_(r), t0_(t0), t1_(t1), acc_(acc), samples_(samples), stop_(t.stop) {
    double step_mult = 1.0;
    if (t.ray_texture) step_mult = read_ray_texture(opt, t_box, x, y);
    lattice_ = ray_lattice(t.plan, fr.view, r, t0);
    lattice_.A *= step_mult;
    lattice_.B *= step_mult;
    last_ = std::min<int64_t>(int64_t(std::floor(lattice_.index_at(t1))), kMaxSamplesPerRay - 1);
    // The chord each sample stands for (midpoint rule): the lattice's [i - 1/2,
    // i + m - 1/2], cut at the ray's entry and exit, so the first sample stands
    // for half a step and the last one for half a step before it and the rest
    // up to the exit (the backends' is chord_at_ends in
    // shaders/ray/lattice.glsl). Virtual samples: the same on the sub-lattice
    // (emit).
    head_ = -(lattice_.t(0.5) - lattice_.t(0.0));
    tail_ = std::min(t1 - lattice_.t(double(last_)), lattice_.step(double(last_), 1)) -
            (lattice_.t(double(last_) + 0.5) - lattice_.t(double(last_)));
  }

  // The walk: every lattice point, or (adaptive) the cells in ray order.
  void run() {
    if (rs_.adaptive ? walk_cells() : walk_points()) return;
    finish();
    close();
    if (t_.projection != Classification::Post) project();
  }

 private:
  struct True {  // a true sample waiting in the virtual samples' window
    double t, f, step;
    glm::dvec3 g;
  };

  // The ray texture's controls (twin of shaders/ray/ray_start.glsl
  // apply_ray_texture): the termination and the DVR/peak blend set here, the
  // step multiplier returned.
  double read_ray_texture(const ReferenceOptions& opt, double t_box, int x, int y) {
    const ResolvedScene& s = fr_.s;
    const glm::dvec2 uv = s.ray_texture->mapping == RayTextureMapping::View
                              ? view_uv(x, y, s.scene.width, s.scene.height)
                              : volume_uv(r_.o + t_box * r_.d, fr_.half);
    const auto c = sample_ray_texture(*t_.ray_texture, uv);
    if (opt.early_termination && t_.projection == Classification::Post)
      stop_ = c[1];  // (a projection never stops by opacity)
    dvr_weight_ = 1.0 - std::max(c[2], 0.0);
    peak_weight_ = 1.0 + std::min(c[2], 0.0);
    return c[0];
  }

  double chord(int64_t i, int m) const {
    double w = lattice_.step(double(i), m);
    if (i == 0) w += head_;
    if (i + m > last_) w += tail_;
    return w;
  }

  // The peaks in the segment from the previous sample to (t, f), composited;
  // true when one was found.
  bool peaks_between(double t, double f) {
    bool hit = false;
    for (double pv : peaks_crossed(t_.table, f_prev_, f, rs_.max_peaks)) {
      const double tr = solve_root(fr_, r_, t_prev_, f_prev_, t, f, pv, rs_.secant_iterations, samples_);
      const glm::dvec4 c = fr_.s.tf.eval(pv);
      acc_.at_t = tr, acc_.at_value = pv;
      acc_.add(fr_.lit(glm::dvec3(c), r_, tr), c.a * peak_weight_);
      hit = true;
      if (acc_.alpha >= stop_) break;
    }
    return hit;
  }

  // One sample (true or virtual) at t with value f, standing for `step`; g: its
  // gradient (raw units) when interpolated, else null and computed at t if
  // shading needs it. True when the ray is opaque. The backends' is consume()
  // in shaders/ray/consume.glsl.
  bool consume(double t, double f, const glm::dvec3* g, double step) {
    if (t_.projection != Classification::Post) {
      gather(t, f, step);
      return false;
    }
    auto lit = [&](const glm::dvec3& rgb) {
      return fr_.shading ? fr_.lit_with(rgb, g ? *g : fr_.grad(r_, t), r_) : rgb;
    };
    const bool peak_hit = t_.peaks_on && !first_ && peaks_between(t, f);
    acc_.at_t = t, acc_.at_value = f;
    if (t_.preint) {
      if (!first_) {
        glm::dvec4 c = lookup_preintegration(t_.pre, f_prev_, f);
        if (t_.varying_steps && c.a > 0) {
          const double a = correct_opacity(c.a, t - t_prev_, t_.dt);
          c = glm::dvec4(glm::dvec3(c) * (a / c.a), a);
        }
        if (c.a > 0) acc_.add(lit(glm::dvec3(c) / c.a), c.a * dvr_weight_);
      }
    } else if (t_.dvr_on && !(peak_hit && rs_.peak_mode == PeakMode::Xor)) {
      const glm::dvec4 c = fr_.s.tf.eval(f);
      if (c.a > 0) acc_.add(lit(glm::dvec3(c)), correct_opacity(c.a, step, fr_.s.tf.opacity_unit) * dvr_weight_);
    }
    t_prev_ = t;
    f_prev_ = f;
    first_ = false;
    return acc_.alpha >= stop_;
  }

  // Intensity projections (the backends' is shaders/ray/projection.glsl): the maximum, the
  // minimum or the chord-weighted mean of every sample's value (in data units), and where the
  // probe places it: at the extreme, or at the chord-weighted centre of the mean's samples; then
  // the TF at that value, its own opacity, composited once.
  void gather(double t, double f, double chord) {
    const bool first = !proj_any_;
    proj_any_ = true;
    proj_len_ += chord;
    if (t_.projection == Classification::Average) {
      proj_ += f * chord;
      proj_t_ += t * chord;
    } else if (first || (t_.projection == Classification::Mip ? f > proj_ : f < proj_)) {
      proj_ = f;
      proj_t_ = t;
    }
  }
  void project() {
    if (!proj_any_) return;
    double v = proj_;
    double at = proj_t_;
    if (t_.projection == Classification::Average) {
      if (!(proj_len_ > 0)) return;
      v = proj_ / proj_len_;
      at = proj_t_ / proj_len_;
    }
    const glm::dvec4 c = fr_.s.tf.eval(v);
    acc_.at_t = at, acc_.at_value = v;
    acc_.add(glm::dvec3(c), c.a * dvr_weight_);
  }

  // Virtual samples (Lee §3.1, §4): the same window of four true samples as the
  // backends' (shaders/ray/virtual_samples.glsl). The segment from window
  // sample a: the true sample, then the Catmull-Rom ones. The sub-samples'
  // chords as the true samples' (chord()), on the sub-lattice: the ray's first
  // sample stands for half a sub-step, and the last before the exit (t_limit,
  // the ray's last segment) for half a sub-step before it and the rest up to
  // the exit.
  bool emit(size_t a, bool has_prev, bool has_next2, double t_limit) {
    const int k = rs_.virtual_samples;
    const double sub = w_[a].step / (k + 1);
    const size_t p0 = has_prev ? a - 1 : a, p3 = has_next2 ? a + 2 : a + 1;
    const double span = w_[a + 1].t - w_[a].t;
    for (int q = 0; q <= k; ++q) {
      const double u = double(q) / (k + 1);
      const double t = w_[a].t + u * span;
      if (q > 0 && t > t_limit) break;
      double weight = sub;
      if (q == 0 && w_[a].t == lattice_.t(0.0)) weight -= 0.5 * sub;
      if (std::isfinite(t_limit) && (q == k || w_[a].t + double(q + 1) / (k + 1) * span > t_limit))
        weight += (t_limit - t) - 0.5 * sub;
      if (q == 0) {
        if (consume(w_[a].t, w_[a].f, &w_[a].g, weight)) return true;
        continue;
      }
      const double f = catmull_rom(w_[p0].f, w_[a].f, w_[a + 1].f, w_[p3].f, u);
      const glm::dvec3 g = catmull_rom(w_[p0].g, w_[a].g, w_[a + 1].g, w_[p3].g, u);
      if (consume(t, f, &g, weight)) return true;
    }
    return false;
  }
  // A true sample into the window; the segment it completes goes out. True when
  // the ray is opaque.
  bool push(const True& s) {
    if (w_.size() == 4) w_.erase(w_.begin());
    w_.push_back(s);
    if (w_.size() == 3) return emit(0, false, true, HUGE_VAL);
    if (w_.size() == 4) return emit(1, true, true, HUGE_VAL);
    return false;
  }
  bool flush() {
    bool done = acc_.alpha >= stop_;
    const size_t n = w_.size();
    if (!done && n >= 2) done = emit(n - 2, n >= 3, false, HUGE_VAL);
    if (!done && n >= 1) done = consume(w_[n - 1].t, w_[n - 1].f, &w_[n - 1].g, w_[n - 1].step);
    w_.clear();
    return done;
  }

  // Visits index i, standing for the m lattice steps after it; true when the
  // ray is opaque.
  bool visit(int64_t i, int m) {
    const double t = lattice_.t(double(i));
    const double step = lattice_.step(double(i), m);
    const double f = fr_.field(r_, t);
    samples_ += 1;
    visited_end_ = i + m;
    if (!rs_.virtual_samples) return consume(t, f, nullptr, chord(i, m));
    return push({t, f, step, fr_.shading ? fr_.grad(r_, t) : glm::dvec3(0.0)});
  }
  bool walk_points() {
    for (int64_t i = 0; i <= last_; ++i)
      if (visit(i, 1)) return true;
    return false;
  }
  // Adaptive: the cells in ray order (the backends' traversal), every m-th
  // index from each cell's first, the last one standing for the steps up to the
  // cell's end.
  bool walk_cells() {
    int64_t next = 0;
    const auto crossings = cells_along(t_.cells, r_, t0_, t1_, fr_.v.spacing, fr_.half);
    for (size_t k = 0; k < crossings.size() && next <= last_; ++k) {
      const CellCrossing& c = crossings[k];
      const bool final_cell = k + 1 == crossings.size();
      const int64_t first_i = int64_t(std::ceil(lattice_.index_at(c.t_in)));
      const int64_t end = final_cell ? last_ : std::min(last_, int64_t(std::ceil(lattice_.index_at(c.t_out))) - 1);
      const int m = t_.multiplier[c.cell];
      for (int64_t i = std::max(next, first_i); i <= end; i += m)
        if (visit(i, int(std::min<int64_t>(m, end + 1 - i)))) return true;
      next = std::max(next, end + 1);
    }
    return false;
  }

  // The ray's end (twin of vs_finish): one more true sample past the exit
  // closes the spline; the virtual samples up to the exit go out.
  void finish() {
    if (!rs_.virtual_samples) return;
    if (acc_.alpha >= stop_ || w_.empty()) return;
    if (w_.back().t != lattice_.t(double(last_))) {
      flush();
      return;
    }
    const double t = lattice_.t(double(last_ + 1));
    samples_ += 1;
    const glm::dvec3 g = fr_.shading ? fr_.grad(r_, t) : glm::dvec3(0.0);
    if (push({t, fr_.field(r_, t), lattice_.step(double(last_ + 1), 1), g})) return;
    emit(w_.size() - 2, w_.size() >= 3, false, t1_);
    w_.clear();
  }
  // Preintegration's last segment, from the last lattice point to the exit (the
  // table's segments cover the chord between samples; the rest of the ray is
  // this one).
  void close() {
    if (!t_.preint || rs_.virtual_samples || first_ || visited_end_ != last_ + 1 || acc_.alpha >= stop_) return;
    const double f = fr_.field(r_, t1_);
    samples_ += 1;
    glm::dvec4 c = lookup_preintegration(t_.pre, f_prev_, f);
    if (!(c.a > 0)) return;
    const double a = correct_opacity(c.a, t1_ - t_prev_, t_.dt);
    acc_.at_t = t1_, acc_.at_value = f;
    acc_.add(fr_.lit(glm::dvec3(c) / c.a, r_, t1_), a * dvr_weight_);
  }

  const Frame& fr_;
  const FrameTables& t_;
  const RenderSettings& rs_;
  const Ray& r_;
  const double t0_, t1_;  // the ray's span
  Accum& acc_;
  double& samples_;
  double stop_, dvr_weight_ = 1.0, peak_weight_ = 1.0;
  RayLattice lattice_;
  int64_t last_ = 0;
  double head_ = 0, tail_ = 0;
  int64_t visited_end_ = -1;  // the last visit's i + m (preintegration closes the ray from it)
  double t_prev_ = 0, f_prev_ = 0;
  bool first_ = true;
  // Projections: the value so far (a mean's sum), the chords, where the probe places it (a mean's
  // sum of t x chord).
  double proj_ = 0, proj_len_ = 0, proj_t_ = 0;
  bool proj_any_ = false;
  std::vector<True> w_;  // waiting true samples, at most 4
};

// The set-up of a reference frame, then `body(pixel)` with the per-ray function
// pixel(ray, t_box, t0, t1, acc, samples, x, y): the whole image, or one pixel
// for a probe.
template <typename Body>
auto run_reference(const Frame& fr, const ReferenceOptions& opt, Body body) {
  const FrameTables tables = make_tables(fr, opt);
  return body([&](const Ray& r, double t_box, double t0, double t1, Accum& acc, double& samples, int x, int y) {
    RefRay(fr, tables, opt, r, t_box, t0, t1, acc, samples, x, y).run();
  });
}

}  // namespace

Image render_reference(const Volume& v, const ResolvedScene& s, const ReferenceOptions& opt) {
  const Frame fr(v, s);
  return run_reference(fr, opt, [&](const auto& pixel) { return for_each_pixel(fr, pixel); });
}

namespace detail {

void with_reference_ray(const Frame& fr, const std::function<void(const PixelRay&)>& body) {
  run_reference(fr, ReferenceOptions{}, [&](const auto& pixel) {
    body(PixelRay(pixel));
    return 0;
  });
}

}  // namespace detail

}  // namespace peakcast::reference
