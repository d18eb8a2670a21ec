// Where a ray's integrand is not smooth, found exactly, for the converged references
// (semi-analytic, docs/accuracy.md): the faces of the voxel cells (the trilinear field changes
// polynomial there) and the crossings of the TF's breakpoints and peak values.
//
// Inside one voxel cell the trilinear field along a ray is a cubic in t: it is rebuilt from four
// samples, split into monotone pieces at the roots of its derivative, and each crossing is
// bisected on the cubic itself. The B-spline field is a degree-9 polynomial per cell; there the
// cell is cut into 8 pieces and crossings are bisected on the field (a double crossing inside
// one eighth of a voxel can be missed).
#pragma once

#include <vector>

#include "core/camera.h"
#include "core/scene.h"
#include "core/volume.h"

namespace peakcast::reference {

struct PeakHit {
  double t;
  double value;
};

struct RaySplit {
  std::vector<double> cuts;    // sorted, including t0 and t1 (and the field's extrema, trilinear)
  std::vector<PeakHit> peaks;  // sorted by t; crossing convention of core/peaks.h
};

RaySplit split_ray(const Volume& v, Filter filter, const Ray& r, const glm::dvec3& half, double t0, double t1,
                   const std::vector<double>& breakpoints, const std::vector<double>& peak_values);

}  // namespace peakcast::reference
