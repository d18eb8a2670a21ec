// Pre-integrated classification baseline (Engel et al. 2001; DESIGN §3): a 2D table of the
// emission-absorption integral over a segment of length `step` whose field runs linearly from
// the front value s_f to the back value s_b.
//
// Entry (i, j): s_f = lo + i/(n-1) (hi-lo), s_b = lo + j/(n-1) (hi-lo); rgb is the segment's
// colour (already weighted by opacity, ready to composite as C += (1 - A) rgb), a its opacity.
// Built in double: the segment is cut into 8 pieces per table bin it crosses and composited
// front to back (self-attenuation included, unlike Engel's integral-function approximation);
// piece opacities depend only on |j - i|, so they are computed once per distance. O(N^3 / 3)
// compositing steps in all, measured in the note. Equal values (i == j) use the 1D TF at that
// value, avoiding the 0/0 of the integral form for tiny delta-f.
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

PreintegrationTable build_preintegration(const TransferFunction& tf, double lo, double hi, double step,
                                         int size = 256);

// The segment integral computed directly (reference for tests), in double.
glm::dvec4 preintegrate_segment(const TransferFunction& tf, double s_front, double s_back, double step,
                                int pieces = 4096);

// Bilinear lookup as the GPU does (texel centres at the entries). C++ twin for the CPU path.
glm::dvec4 lookup_preintegration(const PreintegrationTable& t, double s_front, double s_back);

}  // namespace peakcast
