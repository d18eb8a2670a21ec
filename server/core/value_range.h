// The value range every TF table (colour, peaks, preintegration, occupancy) and the renderers'
// value mapping span: the volume's [min, max], widened to width 1 for a constant volume so that
// nothing divides by zero. One definition, so tables and shaders never disagree on it.
#pragma once

namespace peakcast {

struct ValueRange {
  double lo = 0.0, hi = 1.0;
  double width() const { return hi - lo; }
  double to_unit(double v) const { return (v - lo) / (hi - lo); }  // TF coordinate in [0, 1]
};

inline ValueRange table_range(double lo, double hi) { return {lo, hi > lo ? hi : lo + 1.0}; }

}  // namespace peakcast
