// Pre-integrated classification baseline (Engel et al. 2001): a 2D table of the
// emission-absorption integral over a segment of length `step` whose field runs linearly from
// the front value s_f to the back value s_b.
//
// Entry (i, j): s_f = lo + i/(n-1) (hi-lo), s_b = lo + j/(n-1) (hi-lo); rgb is the segment's
// colour (already weighted by opacity, ready to composite as C += (1 - A) rgb), a its opacity.
// Two builds, both in double:
//  - Exact (default): the segment cut into 8 pieces per bin it crosses and composited front to
//    back, self-attenuation included. Piece opacities depend only on |j - i|; for each distance
//    every window is composited with a sliding-window aggregation (block prefix/suffix
//    composites), so the whole table costs O(N^2 * 8).
//  - Integral: Engel et al.'s O(N^2) integral functions. T(s) = ∫ tau and
//    K(s) = ∫ tau * rgb are tabulated once (8 sub-samples per bin); then each entry is
//    alpha = 1 - exp(-k (T(s_b) - T(s_f))), rgb = k (K(s_b) - K(s_f)) with k = step / (s_b - s_f).
//    Opacity is exact; colour ignores the attenuation inside the segment (so it is clamped to
//    alpha, which an opacity-weighted colour in [0, 1] cannot exceed).
//    Kept for comparison: at step 2 and opacity 0.9 its colour is off by up to 0.42.
// Equal values (i == j) use the 1D TF at that value, avoiding the 0/0 of the integral form.
#pragma once

#include <vector>

#include "core/transfer_function.h"

namespace peakcast {

struct PreintegrationTable {
  int size = 256;
  double lo = 0.0, hi = 1.0, step = 1.0;
  std::vector<float> rgba;  // [j][i][4], i (front) fastest
  double build_ms = 0.0;
};

enum class PreintegrationMethod { Integral, Exact };

PreintegrationTable build_preintegration(const TransferFunction& tf, double lo, double hi, double step, int size = 256,
                                         PreintegrationMethod method = PreintegrationMethod::Exact);

struct RenderSettings;
PreintegrationMethod preint_method(const RenderSettings& r);

// The segment integral computed directly (reference for tests), in double.
glm::dvec4 preintegrate_segment(const TransferFunction& tf, double s_front, double s_back, double step,
                                int pieces = 4096);

// Bilinear lookup as the GPU does (texel centres at the entries). C++ twin for the CPU path.
glm::dvec4 lookup_preintegration(const PreintegrationTable& t, double s_front, double s_back);

}  // namespace peakcast
