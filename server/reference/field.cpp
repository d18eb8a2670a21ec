#include "reference/field.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>

namespace peakcast::reference {
namespace {

inline double voxel(const Volume& v, int64_t i, int64_t j, int64_t k) {
  const auto& d = v.dims();
  i = std::clamp<int64_t>(i, 0, d[0] - 1);
  j = std::clamp<int64_t>(j, 0, d[1] - 1);
  k = std::clamp<int64_t>(k, 0, d[2] - 1);
  return v.value(i, j, k);
}

}  // namespace

double trilinear(const Volume& v, const glm::dvec3& x) {
  const glm::dvec3 f0 = glm::floor(x);
  const glm::dvec3 f = x - f0;
  const int64_t i = int64_t(f0.x), j = int64_t(f0.y), k = int64_t(f0.z);
  double c[2][2];
  for (int b = 0; b < 2; ++b)
    for (int a = 0; a < 2; ++a) c[b][a] = voxel(v, i, j + a, k + b) * (1 - f.x) + voxel(v, i + 1, j + a, k + b) * f.x;
  const double z0 = c[0][0] * (1 - f.y) + c[0][1] * f.y;
  const double z1 = c[1][0] * (1 - f.y) + c[1][1] * f.y;
  return z0 * (1 - f.z) + z1 * f.z;
}

double bspline(const Volume& v, const glm::dvec3& x) {
  const glm::dvec3 f0 = glm::floor(x);
  const glm::dvec3 f = x - f0;
  double w[3][4];
  for (int a = 0; a < 3; ++a) {
    const double t = f[a], t2 = t * t, t3 = t2 * t;
    w[a][0] = (1 - 3 * t + 3 * t2 - t3) / 6;
    w[a][1] = (4 - 6 * t2 + 3 * t3) / 6;
    w[a][2] = (1 + 3 * t + 3 * t2 - 3 * t3) / 6;
    w[a][3] = t3 / 6;
  }
  const int64_t i = int64_t(f0.x) - 1, j = int64_t(f0.y) - 1, k = int64_t(f0.z) - 1;
  double sum = 0;
  for (int c = 0; c < 4; ++c)
    for (int b = 0; b < 4; ++b) {
      double row = 0;
      for (int a = 0; a < 4; ++a) row += w[0][a] * voxel(v, i + a, j + b, k + c);
      sum += w[2][c] * w[1][b] * row;
    }
  return sum;
}

glm::dvec3 gradient(const Volume& v, const glm::dvec3& x, Filter f) {
  glm::dvec3 g;
  for (int a = 0; a < 3; ++a) {
    glm::dvec3 e(0.0);
    e[a] = 1.0;
    g[a] = (sample(v, x + e, f) - sample(v, x - e, f)) / (2.0 * v.spacing[a]);
  }
  return g;
}

}  // namespace peakcast::reference
