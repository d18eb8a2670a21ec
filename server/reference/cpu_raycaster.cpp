#include "reference/cpu_raycaster.h"

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "reference/field.h"
#include "reference/shading.h"

namespace peakcast::reference {

Image render_reference(const Volume& v, const ResolvedScene& s, const ReferenceOptions& opt) {
  const int w = s.scene.width, h = s.scene.height;
  const glm::dvec3 center = (s.box_min + s.box_max) * 0.5, half = (s.box_max - s.box_min) * 0.5;
  const ViewSetup view = setup_view(s.camera, center, w, h);
  const double dt = opt.step > 0 ? opt.step : s.step;
  const double unit = s.tf.opacity_unit;
  const double stop = opt.early_termination ? s.scene.render.early_termination : 2.0;
  const Filter filter = s.scene.render.filter;
  const bool shading = s.scene.render.shading;
  const double lo = v.min_value, hi = v.max_value > v.min_value ? v.max_value : v.min_value + 1.0;
  const double min_spacing = std::min({v.spacing.x, v.spacing.y, v.spacing.z});
  Image img(w, h);
  parallel_for(size_t(h), [&](size_t row) {
    const int y = int(row);
    for (int x = 0; x < w; ++x) {
      const Ray r = make_ray(view, x, y);
      double t0, t1;
      glm::dvec3 rgb(0.0);
      double alpha = 0.0, samples = -1.0;  // -1: the ray misses the box
      if (intersect_box(r, half, t0, t1)) {
        samples = 0.0;
        // Lattice: t0 + i*dt up to t1 (the GPU's). Midpoint: the segment split into n equal
        // pieces of at most dt, sampled at their centres (second order, covers [t0, t1] exactly).
        const int64_t pieces = std::max<int64_t>(1, int64_t(std::ceil((t1 - t0) / dt)));
        const double h = opt.midpoint ? (t1 - t0) / double(pieces) : dt;
        const int64_t last = opt.midpoint ? pieces - 1 : int64_t(std::floor((t1 - t0) / dt));
        for (int64_t i = 0; i <= last; ++i) {
          const double t = t0 + (double(i) + (opt.midpoint ? 0.5 : 0.0)) * h;
          const glm::dvec3 p = r.o + t * r.d;
          const glm::dvec3 xv = (p + half) / v.spacing;
          const glm::dvec4 c = s.tf.eval(sample(v, xv, filter));
          samples += 1;
          if (c.a > 0) {
            glm::dvec3 col(c);
            if (shading) col = shade(col, gradient(v, xv, filter) / (hi - lo), r.d, min_spacing);
            const double a = correct_opacity(c.a, h, unit);
            const double wgt = (1.0 - alpha) * a;
            rgb += wgt * col;
            alpha += wgt;
          }
          if (alpha >= stop) break;
        }
      }
      float* px = img.pixel(x, y);
      const glm::dvec3 out = rgb + (1.0 - alpha) * s.scene.background;
      px[0] = float(out.x);
      px[1] = float(out.y);
      px[2] = float(out.z);
      px[3] = float(alpha);
      img.samples[size_t(y) * w + x] = float(samples);
    }
  });
  return img;
}

ConvergedImage render_converged(const Volume& v, const ResolvedScene& s, double tolerance, double min_step_voxels) {
  ConvergedImage out;
  const double min_spacing = std::min({v.spacing.x, v.spacing.y, v.spacing.z});
  ReferenceOptions opt;
  opt.early_termination = false;
  opt.midpoint = true;
  opt.step = s.step;
  out.image = render_reference(v, s, opt);
  while (opt.step > min_step_voxels * min_spacing) {
    opt.step *= 0.5;
    Image finer = render_reference(v, s, opt);
    double change = 0;
    for (size_t i = 0; i < finer.rgba.size(); ++i)
      if (i % 4 != 3) change = std::max(change, double(std::abs(finer.rgba[i] - out.image.rgba[i])));
    out.image = std::move(finer);
    out.step = opt.step;
    out.last_change = change;
    out.refinements++;
    if (change < tolerance) {
      out.converged = true;
      break;
    }
  }
  return out;
}

}  // namespace peakcast::reference
