// A first transfer function for a volume that came without one, derived from its histogram:
// transparent below the level that splits the values into background and structure (Otsu's
// threshold), then opacity rising with the value through a perceptual colour map (viridis) to
// the 99.9th percentile (mirrored, rising as the value falls to the 0.1th, when the volume's
// faces lie mostly above the threshold: then the high values are the background), scaled so that a ray crossing the box
// gathers most of its opacity inside rather than on the first voxels it meets. With `with_peak` (classification: peaks)
// the TF also gets an opacity peak at the threshold, so peak finding draws the structure's
// surface there.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "core/transfer_function.h"

namespace peakcast {

struct AutoTfInput {
  const std::vector<uint64_t>* histogram = nullptr;  // equal bins over [lo, hi]; may be null
  // The voxels on the volume's faces in the same bins (Volume::border_histogram); may be null.
  // When at least kBackgroundAbove of them lie above the threshold, the background is the upper
  // class (a signed distance field, a dark stain on a bright field) and the TF is mirrored.
  const std::vector<uint64_t>* border_histogram = nullptr;
  double lo = 0.0, hi = 1.0;
  // A ray's typical length through the box, in opacity units (the smallest spacing).
  double ray_length = 100.0;
  bool with_peak = false;
};

// Where the histogram splits into two classes with the largest between-class variance: the
// value at the boundary of the bins (lo when the histogram is empty or constant).
double otsu_threshold(const std::vector<uint64_t>& histogram, double lo, double hi);

// The share of the faces' voxels above which the upper class is taken for the background.
constexpr double kBackgroundAbove = 0.75;

TransferFunction derive_transfer_function(const AutoTfInput& in);

// viridis (matplotlib's perceptual map) at t in [0, 1]: sRGB values in [0, 1].
glm::dvec3 viridis(double t);

}  // namespace peakcast
