// The reference's arithmetic twins of the backends' shared functions (shaders/ray/), in double:
// the Catmull-Rom spline of virtual samples and the regula falsi of peak finding. Internal to the
// reference renderer (reference_renderer.cpp).
#pragma once

#include <algorithm>

#include "reference/ray_frame.h"

namespace peakcast::reference::detail {

// Catmull-Rom through p0..p3, between p1 (u = 0) and p2 (u = 1): twin of the
// shader's.
template <typename T>
inline T catmull_rom(const T& p0, const T& p1, const T& p2, const T& p3, double u) {
  return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * u * u +
                (3.0 * p1 - p0 - 3.0 * p2 + p3) * u * u * u);
}

// The backends' is solve_root in shaders/ray/peaks.glsl.
inline double solve_root(const Frame& fr, const Ray& r, double t0, double f0, double t1, double f1, double v, int iters,
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

}  // namespace peakcast::reference::detail
