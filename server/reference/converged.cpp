// The converged reference (reference_renderer.h render_converged): the optical model itself, the ray
// cut at voxel faces and TF breakpoints, each piece integrated by the midpoint rule and refined
// until the image stops changing.
#include "reference/reference_renderer.h"

#include <algorithm>
#include <cmath>

#include "core/peaks.h"
#include "reference/ray_events.h"
#include "reference/ray_frame.h"

namespace peakcast::reference {

using namespace detail;

namespace {

// The peaks of sp at or before t (from next_peak on), composited as surfaces.
void add_peaks_until(const Frame& fr, const Ray& r, const RaySplit& sp, double t, size_t& next_peak, Accum& acc) {
  while (next_peak < sp.peaks.size() && sp.peaks[next_peak].t <= t) {
    const glm::dvec4 col = fr.s.tf.eval(sp.peaks[next_peak].value);
    acc.add(fr.lit(glm::dvec3(col), r, sp.peaks[next_peak].t), col.a);
    ++next_peak;
  }
}

// One ray's integral with steps of at most `step`: each piece between two cuts by the midpoint
// rule, the surfaces at the cuts between them.
void integrate_ray(const Frame& fr, const Ray& r, const RaySplit& sp, double step, Accum& acc, double& samples) {
  const ResolvedScene& s = fr.s;
  size_t next_peak = 0;
  for (size_t c = 0; c + 1 < sp.cuts.size(); ++c) {
    const double a = sp.cuts[c], b = sp.cuts[c + 1];
    add_peaks_until(fr, r, sp, a, next_peak, acc);  // surfaces at this cut
    if (b <= a) continue;
    // Midpoint steps of at most `step`, and small enough that opacity changes by at most
    // `da` per step: inside a Dirac-like tent the field lingers where the TF is steep.
    const double da = 0.02 * step / s.step;
    const double a0 = s.tf.eval(fr.field(r, a)).a, a1 = s.tf.eval(fr.field(r, b)).a;
    const int pieces =
        std::min(1 << 16, std::max({1, int(std::ceil((b - a) / step)), int(std::ceil(std::abs(a1 - a0) / da))}));
    const double hstep = (b - a) / pieces;
    for (int q = 0; q < pieces; ++q) {
      const double t = a + (q + 0.5) * hstep;
      const glm::dvec4 col = s.tf.eval(fr.field(r, t));
      samples += 1;
      if (col.a > 0) acc.add(fr.lit(glm::dvec3(col), r, t), correct_opacity(col.a, hstep, s.tf.opacity_unit));
    }
  }
  add_peaks_until(fr, r, sp, HUGE_VAL, next_peak, acc);
}

// Each pixel's ray cut at voxel faces, TF breakpoints and (peaks) surfaces; hit[k] 0 where the
// ray draws nothing. The splits do not depend on the step: found once per pixel.
void split_rays(const Frame& fr, OpticalModel model, std::vector<RaySplit>& splits, std::vector<char>& hit) {
  const ResolvedScene& s = fr.s;
  std::vector<double> breakpoints, peak_values;
  for (const auto& p : s.tf.points) breakpoints.push_back(p.value);
  if (model == OpticalModel::Peaks)
    for (const auto& p : find_peaks(s.tf)) peak_values.push_back(p.value);
  const int w = s.scene.width, h = s.scene.height;
  splits.assign(size_t(w) * h, RaySplit{});
  hit.assign(splits.size(), 0);
  parallel_for(size_t(h), [&](size_t row) {
    for (int x = 0; x < w; ++x) {
      const Ray r = make_ray(fr.view, x, int(row));
      double t_box, t0, t1;
      bool missed;
      const size_t k = row * size_t(w) + size_t(x);
      if (fr.span(r, t_box, t0, t1, missed)) {
        hit[k] = 1;
        splits[k] = split_ray(fr.v, fr.filter, r, fr.half, t0, t1, breakpoints, peak_values);
      }
    }
  });
}

}  // namespace

ConvergedImage render_converged(const Volume& v, const ResolvedScene& s, OpticalModel model, double tolerance,
                                double min_step_voxels) {
  const Frame fr(v, s);
  std::vector<RaySplit> splits;
  std::vector<char> hit;
  split_rays(fr, model, splits, hit);
  const int w = s.scene.width, h = s.scene.height;
  auto render_at = [&](double step) {
    // Misses keep the background (for_each_pixel with nothing to integrate), hits are filled below.
    Image img = for_each_pixel(fr, [](const Ray&, double, double, double, Accum&, double&, int, int) {});
    parallel_for(size_t(h), [&](size_t row) {
      for (int x = 0; x < w; ++x) {
        const size_t k = row * size_t(w) + size_t(x);
        if (!hit[k]) continue;
        Accum acc;
        double samples = 0;
        integrate_ray(fr, make_ray(fr.view, x, int(row)), splits[k], step, acc, samples);
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
