// A synthetic angiography volume (`peakcast make-volume vessels`): a branching tree of
// contrast-filled tubes with a saccular aneurysm at its first bifurcation, on dim soft tissue
// (Knoll Fig. 6/7's "aneurism" scenes, without the licence). Tubes have a smooth edge about a
// voxel wide, radii from ~4.5% of the smallest dimension down to one voxel, so near and far
// views see features from many pixels wide to sub-pixel.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "core/volume.h"

namespace peakcast {

struct VesselTree {
  struct Tube {
    glm::dvec3 a, b;  // end points, voxel coordinates
    double radius;    // voxels
  };
  std::vector<Tube> tubes;
  glm::dvec3 sac_center{0.0};  // the aneurysm, voxel coordinates
  double sac_radius = 0.0;
  uint64_t seed = 1;

  // Value in [0, 1] at voxel (i, j, k): tissue ~0.1, lumen ~0.92.
  double value(int64_t i, int64_t j, int64_t k) const;
};

// Pure function of (seed, dims): 63 tubes in six generations.
VesselTree make_vessel_tree(uint64_t seed, const Dims& dims);

}  // namespace peakcast
