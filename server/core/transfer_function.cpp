#include "core/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace peakcast {

glm::dvec4 TransferFunction::eval(double v) const {
  if (points.empty()) return glm::dvec4(0.0);
  auto rgba = [](const TfPoint& p) { return glm::dvec4(p.r, p.g, p.b, p.a); };
  auto it = std::upper_bound(points.begin(), points.end(), v, [](double x, const TfPoint& p) { return x < p.value; });
  if (it == points.begin()) return rgba(points.front());
  if (it == points.end()) return rgba(points.back());
  const TfPoint& a = *(it - 1);
  const TfPoint& b = *it;
  const double w = (v - a.value) / (b.value - a.value);  // b.value > a.value by upper_bound
  return rgba(a) + (rgba(b) - rgba(a)) * w;
}

double TransferFunction::max_opacity(double lo, double hi) const {
  double m = std::max(eval(lo).a, eval(hi).a);
  for (const auto& p : points)
    if (p.value > lo && p.value < hi) m = std::max(m, p.a);
  return m;
}

std::vector<float> TransferFunction::bake(int n, double lo, double hi) const {
  std::vector<float> table(size_t(n) * 4);
  for (int k = 0; k < n; ++k) {
    const glm::dvec4 c = eval(lo + (hi - lo) * double(k) / double(n - 1));
    for (int ch = 0; ch < 4; ++ch) table[size_t(k) * 4 + ch] = float(c[ch]);
  }
  return table;
}

std::string TransferFunction::to_string() const {
  std::ostringstream s;
  s << "TF{" << points.size() << " points";
  for (const auto& p : points) s << " [" << p.value << ": " << p.r << "," << p.g << "," << p.b << "," << p.a << "]";
  s << ", opacity_unit " << opacity_unit << "}";
  return s.str();
}

TransferFunction TransferFunction::grey_ramp(double lo, double hi) {
  TransferFunction tf;
  tf.points = {{lo, 0, 0, 0, 0}, {hi, 1, 1, 1, 1}};
  return tf;
}

double correct_opacity(double a, double dt, double unit) {
  return 1.0 - std::pow(std::max(1.0 - std::clamp(a, 0.0, 1.0), 0.0), dt / unit);
}

}  // namespace peakcast
