#include "core/preintegration.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/vec3.hpp>

#include "core/parallel.h"
#include "core/value_range.h"

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

namespace {

// The TF sampled at the centres of `sub` sub-bins per bin of the table: extinction and colour.
struct SubBins {
  int sub = 8;
  double ds = 0;  // a bin's width in field values
  std::vector<double> tau;
  std::vector<glm::dvec3> col;
};

void store(PreintegrationTable& t, int i, int j, const glm::dvec3& c, double a) {
  float* out = &t.rgba[(size_t(j) * t.size + size_t(i)) * 4];
  out[0] = float(c.r), out[1] = float(c.g), out[2] = float(c.b), out[3] = float(a);
}

// The integral method: prefix integrals over the field value, in units of one sub-bin.
void fill_integral(PreintegrationTable& t, const SubBins& b, double step) {
  const int n = t.size, sub = b.sub;
  const double ds = b.ds;
  const std::vector<double>& tau = b.tau;
  const std::vector<glm::dvec3>& col = b.col;
  std::vector<double> T(tau.size() + 1, 0.0);
  std::vector<glm::dvec3> K(tau.size() + 1, glm::dvec3(0.0));
  const double dsub = ds / sub;
  for (size_t q = 0; q < tau.size(); ++q) {
    T[q + 1] = T[q] + tau[q] * dsub;
    K[q + 1] = K[q] + tau[q] * col[q] * dsub;
  }
  parallel_for(size_t(n), [&](size_t jj) {
    const int j = int(jj);
    for (int i = 0; i < n; ++i) {
      if (i == j) continue;
      const size_t qf = size_t(i) * sub, qb = size_t(j) * sub;
      const double k = step / ((j - i) * ds);  // world length per unit of field value (signed)
      const double a = 1.0 - std::exp(-std::abs(k * (T[qb] - T[qf])));
      glm::dvec3 c = k * (K[qb] - K[qf]);
      for (int ch = 0; ch < 3; ++ch) c[ch] = std::clamp(c[ch], 0.0, a);
      store(t, i, j, c, a);
    }
  });
}

void fill_exact(PreintegrationTable& t, const SubBins& b, double step) {
  const int n = t.size, sub = b.sub;
  const std::vector<double>& tau = b.tau;
  const std::vector<glm::dvec3>& col = b.col;
  // Exact: for |j - i| = d the segment crosses L = d * sub sub-bins of length step / L, so the
  // sub-bin opacities depend on d only. Every window of L consecutive sub-bins is composited
  // front to back with the sliding-window trick for an associative operator: cut the sub-bins
  // into blocks of L, keep prefix and suffix composites per block, and a window is one suffix
  // composited with one prefix. O(N * sub) per d, O(N^2 * sub) in all, each entry exact.
  struct Acc {
    glm::dvec3 c{0.0};
    double a = 0.0;
  };
  auto over = [](const Acc& f, const Acc& b) { return Acc{f.c + (1.0 - f.a) * b.c, f.a + (1.0 - f.a) * b.a}; };
  const int m = int(tau.size());
  parallel_for(size_t(n - 1), [&](size_t dd) {
    const int d = int(dd) + 1, L = d * sub;
    const double h = step / L;
    std::vector<Acc> e(static_cast<size_t>(m)), pre(static_cast<size_t>(m)), suf(static_cast<size_t>(m));
    for (int dir : {1, -1}) {        // rising field (front bin i, back i + d), then falling
      for (int q = 0; q < m; ++q) {  // element k is the k-th sub-bin in ray order
        const size_t src = size_t(dir > 0 ? q : m - 1 - q);
        const double a = 1.0 - std::exp(-tau[src] * h);
        e[size_t(q)] = {a * col[src], a};
      }
      for (int q = 0; q < m; ++q) pre[size_t(q)] = q % L == 0 ? e[size_t(q)] : over(pre[size_t(q - 1)], e[size_t(q)]);
      for (int q = m - 1; q >= 0; --q)
        suf[size_t(q)] = (q % L == L - 1 || q == m - 1) ? e[size_t(q)] : over(e[size_t(q)], suf[size_t(q + 1)]);
      for (int i = 0; i + d < n; ++i) {
        const int qs = dir > 0 ? i * sub : m - (i + d) * sub;  // first element of the window
        const int qe = qs + L - 1;
        const Acc w = (qs / L == qe / L) ? suf[size_t(qs)] : over(suf[size_t(qs)], pre[size_t(qe)]);
        if (dir > 0)
          store(t, i, i + d, w.c, w.a);
        else
          store(t, i + d, i, w.c, w.a);
      }
    }
  });
}

}  // namespace

PreintegrationTable build_preintegration(const TransferFunction& tf, double lo, double hi, double step, int n,
                                         PreintegrationMethod method) {
  const auto t0 = std::chrono::steady_clock::now();
  PreintegrationTable t;
  t.size = n;
  t.lo = lo;
  t.hi = table_range(lo, hi).hi;
  t.step = step;
  t.rgba.assign(size_t(n) * n * 4, 0.f);
  SubBins b;
  b.ds = (t.hi - lo) / (n - 1);
  b.tau.resize(size_t(n - 1) * b.sub);
  b.col.resize(b.tau.size());
  for (size_t q = 0; q < b.tau.size(); ++q) {
    const glm::dvec4 e = tf.eval(lo + b.ds * (double(q) + 0.5) / b.sub);
    b.tau[q] = extinction(e.a, tf.opacity_unit);
    b.col[q] = glm::dvec3(e);
  }
  for (int i = 0; i < n; ++i) {  // guard: no field change, the 1D TF at the value
    const glm::dvec4 e = tf.eval(lo + b.ds * i);
    const double a = correct_opacity(e.a, step, tf.opacity_unit);
    store(t, i, i, glm::dvec3(e) * a, a);
  }
  if (method == PreintegrationMethod::Integral)
    fill_integral(t, b, step);
  else
    fill_exact(t, b, step);
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
  return (at(x0, y0) * (1 - fx) + at(x0 + 1, y0) * fx) * (1 - fy) +
         (at(x0, y0 + 1) * (1 - fx) + at(x0 + 1, y0 + 1) * fx) * fy;
}

}  // namespace peakcast
