#include "core/preintegration.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/vec3.hpp>

#include "core/parallel.h"

namespace peakcast {
namespace {

// Extinction per world unit of opacity a per `unit` world units.
double extinction(double a, double unit) { return -std::log(std::max(1.0 - std::clamp(a, 0.0, 1.0), 1e-12)) / unit; }

}  // namespace

glm::dvec4 preintegrate_segment(const TransferFunction& tf, double sf, double sb, double step, int pieces) {
  glm::dvec3 c(0.0);
  double alpha = 0.0;
  const double h = step / pieces;
  for (int k = 0; k < pieces; ++k) {
    const double s = sf + (sb - sf) * (k + 0.5) / pieces;
    const glm::dvec4 q = tf.eval(s);
    const double a = 1.0 - std::exp(-extinction(q.a, tf.opacity_unit) * h);
    c += (1.0 - alpha) * a * glm::dvec3(q);
    alpha += (1.0 - alpha) * a;
  }
  return {c, alpha};
}

PreintegrationTable build_preintegration(const TransferFunction& tf, double lo, double hi, double step, int n) {
  const auto t0 = std::chrono::steady_clock::now();
  PreintegrationTable t;
  t.size = n;
  t.lo = lo;
  t.hi = hi > lo ? hi : lo + 1.0;
  t.step = step;
  t.rgba.assign(size_t(n) * n * 4, 0.f);
  const double ds = (t.hi - lo) / (n - 1);
  // The TF sampled at the centres of `sub` sub-bins per bin: extinction and colour.
  const int sub = 8;
  std::vector<double> tau(size_t(n - 1) * sub);
  std::vector<glm::dvec3> col(tau.size());
  for (size_t q = 0; q < tau.size(); ++q) {
    const glm::dvec4 e = tf.eval(lo + ds * (double(q) + 0.5) / sub);
    tau[q] = extinction(e.a, tf.opacity_unit);
    col[q] = glm::dvec3(e);
  }
  auto store = [&](int i, int j, const glm::dvec3& c, double a) {
    float* out = &t.rgba[(size_t(j) * n + size_t(i)) * 4];
    out[0] = float(c.r), out[1] = float(c.g), out[2] = float(c.b), out[3] = float(a);
  };
  for (int i = 0; i < n; ++i) {  // guard: no field change, the 1D TF at the value
    const glm::dvec4 e = tf.eval(lo + ds * i);
    const double a = correct_opacity(e.a, step, tf.opacity_unit);
    store(i, i, glm::dvec3(e) * a, a);
  }
  // For |j - i| = d the segment crosses d * sub sub-bins, each of length step / (d * sub): their
  // opacities depend on d only, so they are computed once per d; then every (i, j) at that
  // distance composites its sub-bins front to back, in ray order.
  parallel_for(size_t(n - 1), [&](size_t dd) {
    const int d = int(dd) + 1, count = d * sub;
    const double h = step / count;
    std::vector<double> a(tau.size());
    for (size_t q = 0; q < tau.size(); ++q) a[q] = 1.0 - std::exp(-tau[q] * h);
    for (int i = 0; i + d < n; ++i) {
      for (int dir : {1, -1}) {
        const int front = dir > 0 ? i : i + d, back = dir > 0 ? i + d : i;
        glm::dvec3 c(0.0);
        double alpha = 0.0;
        for (int m = 0; m < count; ++m) {
          const size_t q = size_t(dir > 0 ? front * sub + m : front * sub - 1 - m);
          const double w = (1.0 - alpha) * a[q];
          c += w * col[q];
          alpha += w;
        }
        store(front, back, c, alpha);
      }
    }
  });
  t.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

glm::dvec4 lookup_preintegration(const PreintegrationTable& t, double sf, double sb) {
  const int n = t.size;
  auto coord = [&](double s) { return std::clamp((s - t.lo) / (t.hi - t.lo) * (n - 1), 0.0, double(n - 1)); };
  const double x = coord(sf), y = coord(sb);
  const int x0 = std::min(int(x), n - 2), y0 = std::min(int(y), n - 2);
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int i, int j) {
    const float* p = &t.rgba[(size_t(j) * n + size_t(i)) * 4];
    return glm::dvec4(p[0], p[1], p[2], p[3]);
  };
  return (at(x0, y0) * (1 - fx) + at(x0 + 1, y0) * fx) * (1 - fy) + (at(x0, y0 + 1) * (1 - fx) + at(x0 + 1, y0 + 1) * fx) * fy;
}

}  // namespace peakcast
