// What every reference ray shares (reference_renderer.cpp, converged.cpp): the frame of a scene (view,
// range, filter, clip), the front-to-back accumulator, and the loop over an image's pixels.
// Internal to the reference renderer.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/camera.h"
#include "core/clip.h"
#include "core/image.h"
#include "core/parallel.h"
#include "core/scene.h"
#include "core/value_range.h"
#include "core/volume.h"
#include "reference/field.h"
#include "reference/shading.h"

namespace peakcast::reference::detail {

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
  // A probe's first visible surface: the first add whose value the TF gives an opacity of at
  // least pick_opacity (probes only: null while rendering).
  const TransferFunction* pick_tf = nullptr;
  double pick_opacity = 0.0;
  double first_t = std::nan(""), first_value = 0.0;
  void add(const glm::dvec3& c, double a) {
    const double w = (1.0 - alpha) * a;
    if (alpha < 0.5 && alpha + w >= 0.5 && std::isnan(half_t)) half_t = at_t, half_value = at_value;
    if (pick_tf && a > 0.0 && std::isnan(first_t) && pick_tf->eval(at_value).a >= pick_opacity)
      first_t = at_t, first_value = at_value;
    rgb += w * c;
    alpha += w;
  }
};

// The reference ray of a frame's method for one pixel, behind std::function (probe.cpp): its tables
// are built once, before `body` runs; `pixel` may be called from several threads at once.
using PixelRay =
    std::function<void(const Ray& r, double t_box, double t0, double t1, Accum& acc, double& samples, int x, int y)>;
void with_reference_ray(const Frame& fr, const std::function<void(const PixelRay&)>& body);

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

}  // namespace peakcast::reference::detail
