// Piecewise-linear transfer function in the volume's native data units (docs/scenes.md):
// points {value, r, g, b, a} sorted by value, linear between, constant outside; two points may
// share a value (a step: at that value and above, the later point holds). `a` is opacity per
// `opacity_unit` world units.
#pragma once

#include <string>
#include <vector>

#include <glm/vec4.hpp>

namespace peakcast {

struct TfPoint {
  double value = 0, r = 0, g = 0, b = 0, a = 0;
};

struct TransferFunction {
  std::vector<TfPoint> points;
  double opacity_unit = 0.0;  // 0: the volume's smallest spacing

  glm::dvec4 eval(double value) const;  // rgba
  // Largest opacity over [lo, hi] of the continuous function.
  double max_opacity(double lo, double hi) const;
  // RGBA table of n entries sampling [lo, hi] at entries' centres: entry k at lo + k/(n-1)*(hi-lo).
  std::vector<float> bake(int n, double lo, double hi) const;
  std::string to_string() const;

  static constexpr int kTableSize = 8192;
  // A grey ramp from transparent at lo to opaque white at hi.
  static TransferFunction grey_ramp(double lo, double hi);
};

// 1 - (1 - a)^(dt / unit), with a clamped to [0, 1].
double correct_opacity(double a, double dt, double unit);

}  // namespace peakcast
