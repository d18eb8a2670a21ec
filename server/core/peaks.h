// Peak finding's transfer-function side (Knoll et al. 2009 §4.1, errata in docs/architecture.md):
// the peaks of the TF's opacity and the 2D peak table.
//
// A peak is a local maximum of the piecewise-linear opacity: a point, or a run of points of
// equal opacity (a plateau, including a step made of two points sharing a value), whose
// neighbours on both sides are lower. A plateau counts once, at the middle of its values.
// Maxima at the TF's ends are not peaks (the TF is constant beyond them, so they are plateaus
// that never descend on one side; DVR already renders them).
//
// Bracketing (the errata): a segment whose field goes from f0 to f1 crosses the peak value v
// when min(f0, f1) < v <= max(f0, f1). Both samples equal to v is no crossing.
//
// The table: bins x bins texels; bin k holds field values [lo + k w, lo + (k + 1) w), the last
// bin also hi. Texel (i, j) lists every peak value that SOME pair f0 in bin i, f1 in bin j
// brackets, in ray order (ascending when i < j, descending when i > j, ascending on the
// diagonal, where the shader reverses for falling segments). Each texel holds four values per
// layer; a table has as many layers as its fullest texel needs (usually one), so nothing is
// lost to quantisation or capacity. Unused slots hold kNoPeak.
#pragma once

#include <vector>

#include <glm/vec4.hpp>

#include "core/transfer_function.h"

namespace peakcast {

struct Peak {
  double value = 0.0;
  glm::dvec4 rgba{0.0};  // the TF at the peak value
};

std::vector<Peak> find_peaks(const TransferFunction& tf);

struct PeakTable {
  static constexpr double kNoPeak = -1e300;
  int bins = 128;
  int layers = 1;
  double lo = 0.0, hi = 1.0;
  std::vector<double> texels;  // [layer][j][i][4] in data units; i (entry bin) fastest
  double build_ms = 0.0;

  int bin_of(double f) const;
  const double* texel(int i, int j, int layer) const {
    return &texels[((size_t(layer) * bins + size_t(j)) * bins + size_t(i)) * 4];
  }
};

// Peaks outside [lo, hi] can never be crossed and are left out.
PeakTable build_peak_table(const std::vector<Peak>& peaks, double lo, double hi, int bins = 128);

// The C++ twin of the shader's lookup: the first `max_peaks` peak values that the segment
// f0 -> f1 really crosses, in ray order.
std::vector<double> peaks_crossed(const PeakTable& table, double f0, double f1, int max_peaks = 4);

// Exact answer for tests: every peak value in (min, max], in ray order, at most max_peaks.
std::vector<double> peaks_crossed_exact(const std::vector<Peak>& peaks, double f0, double f1, int max_peaks = 4);

inline bool crosses(double f0, double f1, double v) { return std::min(f0, f1) < v && v <= std::max(f0, f1); }

}  // namespace peakcast
