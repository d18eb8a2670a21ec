#include "reference/ray_events.h"

#include <algorithm>
#include <cmath>

#include "reference/field.h"

namespace peakcast::reference {
namespace {

struct Cubic {
  double c[4];  // p(u) = c0 + c1 u + c2 u^2 + c3 u^3 on u in [0, 1]
  double operator()(double u) const { return c[0] + u * (c[1] + u * (c[2] + u * c[3])); }
};

// Interpolates samples at u = 0, 1/3, 2/3, 1 (exact for a cubic).
Cubic fit(double y0, double y1, double y2, double y3) {
  Cubic p;
  p.c[0] = y0;
  p.c[1] = (-11 * y0 + 18 * y1 - 9 * y2 + 2 * y3) / 2;
  p.c[2] = (18 * y0 - 45 * y1 + 36 * y2 - 9 * y3) / 2;
  p.c[3] = (-9 * y0 + 27 * y1 - 27 * y2 + 9 * y3) / 2;
  return p;
}

// Crossing of value v on [a, b] where (f(a) >= v) != (f(b) >= v), by bisection.
template <typename F>
double bisect(const F& f, double a, double b, double v) {
  const bool above_a = f(a) >= v;
  for (int k = 0; k < 60 && b - a > 1e-14 * (1 + std::abs(a)); ++k) {
    const double m = 0.5 * (a + b);
    if ((f(m) >= v) == above_a)
      a = m;
    else
      b = m;
  }
  return b;  // the first point at the far side: matches "crossed when (min, max]"
}

}  // namespace

RaySplit split_ray(const Volume& vol, Filter filter, const Ray& r, const glm::dvec3& half, double t0, double t1,
                   const std::vector<double>& breakpoints, const std::vector<double>& peak_values) {
  RaySplit out;
  // Voxel-cell faces: planes x = integer in voxel coordinates.
  std::vector<double> faces = {t0, t1};
  for (int a = 0; a < 3; ++a) {
    const double dv = r.d[a] / vol.spacing[a];
    if (std::abs(dv) < 1e-15) continue;
    const double x0 = (r.o[a] + t0 * r.d[a] + half[a]) / vol.spacing[a];
    const double x1 = (r.o[a] + t1 * r.d[a] + half[a]) / vol.spacing[a];
    for (double k = std::ceil(std::min(x0, x1)); k <= std::floor(std::max(x0, x1)); k += 1.0) {
      const double t = t0 + (k - x0) / dv;
      if (t > t0 && t < t1) faces.push_back(t);
    }
  }
  std::sort(faces.begin(), faces.end());
  out.cuts = faces;
  auto field = [&](double t) { return sample(vol, (r.o + t * r.d + half) / vol.spacing, filter); };
  for (size_t c = 0; c + 1 < faces.size(); ++c) {
    const double ta = faces[c], tb = faces[c + 1];
    if (tb - ta <= 0) continue;
    // Monotone pieces [ua, ub] (in t) with a function to bisect on.
    std::vector<double> knots = {ta};
    Cubic p{};
    // Trilinear: along the ray inside one cell the field is exactly a cubic polynomial in t.
    const bool field_is_cubic_in_t = filter == Filter::Trilinear;
    double end_value = 0.0;  // the field at tb, as sampled: the next cell starts from the same value
    if (field_is_cubic_in_t) {
      end_value = field(tb);
      p = fit(field(ta), field(ta + (tb - ta) / 3), field(ta + 2 * (tb - ta) / 3), end_value);
      // Roots of p'(u) = c1 + 2 c2 u + 3 c3 u^2 inside (0, 1).
      const double A = 3 * p.c[3], B = 2 * p.c[2], C = p.c[1];
      std::vector<double> us;
      if (std::abs(A) > 1e-300) {
        const double disc = B * B - 4 * A * C;
        if (disc >= 0) {
          const double s = std::sqrt(disc);
          us = {(-B - s) / (2 * A), (-B + s) / (2 * A)};
        }
      } else if (std::abs(B) > 1e-300) {
        us = {-C / B};
      }
      std::sort(us.begin(), us.end());
      for (double u : us)
        if (u > 0 && u < 1) {
          knots.push_back(ta + u * (tb - ta));
          out.cuts.push_back(knots.back());  // extrema cut too: every piece is monotone
        }
    } else {
      for (int k = 1; k < 8; ++k) knots.push_back(ta + (tb - ta) * k / 8.0);
    }
    knots.push_back(tb);
    // At the cell's end the sample itself, not the cubic's rounding of it: a crossing exactly at
    // a cell face (the data equal to a peak value there) would otherwise fall between two cells.
    auto f = [&](double t) {
      if (!field_is_cubic_in_t) return field(t);
      return t == tb ? end_value : p((t - ta) / (tb - ta));
    };
    for (size_t k = 0; k + 1 < knots.size(); ++k) {
      const double a = knots[k], b = knots[k + 1];
      const double fa = f(a), fb = f(b);
      const double lo = std::min(fa, fb), hi = std::max(fa, fb);
      for (double v : breakpoints)
        if (v > lo && v <= hi) out.cuts.push_back(bisect(f, a, b, v));
      for (double v : peak_values)
        if (v > lo && v <= hi) out.peaks.push_back({bisect(f, a, b, v), v});
    }
  }
  for (const auto& h : out.peaks) out.cuts.push_back(h.t);
  std::sort(out.cuts.begin(), out.cuts.end());
  std::sort(out.peaks.begin(), out.peaks.end(), [](const PeakHit& x, const PeakHit& y) { return x.t < y.t; });
  return out;
}

}  // namespace peakcast::reference
