// Where the samples of a ray lie (docs/scenes.md "Sampling"; Knoll §5-§6.2). One definition for
// the reference (reference/); the GL and CPU backends share theirs in shaders/ray/lattice.glsl.
//
// Every ray samples a lattice that starts at its entry into the box:
//     t_j = t_enter + j * (B + A * j / 2),   j = 0, 1, 2, ...
// computed from j (never accumulated), relative to the box entry (a local origin: no
// cancellation for a camera far away). Uniform sampling: A = 0, B = the step.
// Differential sampling (Knoll eq. 14-18): the eye-based sequence T(x) = a x^2 / 2 + b x with
// b = k and a = k * |dD/dx| (eq. 10, per ray), entered at the box: A = a,
// B = max(b + a * x_enter, min_step), where T(x_enter) is the eye-to-entry distance. The step
// t_{j+1} - t_j grows by a per sample, so at a distance d from the eye it is
// sqrt(k^2 + 2 k |dD/dx| d). k is chosen so that s_k means what it says: where the central ray
// crosses the focal plane (through the camera's center, at distance f) the step is s_k * F,
// F = |u dx + v dy| f the world-space footprint of a pixel's diagonal there:
// k^2 + 2 k g = (s_k F)^2 with g = |dD/dx| f (Knoll's k = s_k * F would put that step at
// about sqrt(2 s_k) F instead). Nearer than f the step is longer than s_k times the local
// footprint (by about sqrt(f / d)), farther it is shorter. Orthographic cameras have a constant
// footprint: differential sampling there is uniform at step max(s_k * F, min_step).
// Adaptive sampling (Knoll §6.2): a macrocell with multiplier M visits every M-th lattice index
// from its first (eq. 19 is exactly that for the differential lattice); each sample stands for
// the steps up to the next one (the cell's last: up to the cell's end), t_{j+m} - t_j, so the
// cells cover the ray without gaps or overlaps and opacity is corrected for the step taken.
#pragma once

#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/macrocells.h"
#include "core/scene.h"

namespace peakcast {

// Lattice points a ray visits at most (guards runaway loops; the GPU and the CPU twin stop at
// the same index). Rays that reach it are counted in the frame stats (rays_at_sample_cap).
constexpr int kMaxSamplesPerRay = 1 << 20;

// No step below this fraction of the smallest spacing (the converged reference's finest step):
// keeps s_k -> 0 finite and bounded in time.
constexpr double kMinDifferentialStepFraction = 1.0 / 64.0;

struct SamplingPlan {
  bool differential = false;  // perspective camera with sampling = differential
  double step = 1.0;          // uniform step (also orthographic "differential")
  double k = 0.0;             // differential: b of Knoll's eq. 17 (see above)
  double footprint = 0.0;     // differential: F, a pixel diagonal's footprint at the focal distance
  double min_step = 0.0;      // differential: lower bound of every step
  double pixel_du = 0.0;      // image-plane pixel width per unit depth (|u dx| in eq. 10)
};

// `step_scale` coarsens the plan (interactive frames): the uniform step, or s_k, times it.
SamplingPlan plan_sampling(const ResolvedScene& s, double step_scale = 1.0);

struct RayLattice {
  double t0 = 0.0, A = 0.0, B = 1.0;
  double t(double j) const { return t0 + j * (B + A * j * 0.5); }
  // t(j + m) - t(j) without cancellation: the step a sample visited with stride m stands for.
  double step(double j, int m) const { return m * (B + A * (j + 0.5 * m)); }
  // The continuous index x with t(x) = t, for t >= t0 (stable form: no cancellation when A -> 0).
  double index_at(double t) const;
};

// The lattice of ray `r` entering the box at `t_enter`.
RayLattice ray_lattice(const SamplingPlan& plan, const ViewSetup& view, const Ray& r, double t_enter);

// The longest step any ray of the scene takes (world units, before adaptive multipliers):
// the uniform step, or for differential sampling the step at the box corner farthest from the
// eye, sqrt(b^2 + 2 a d) + a/2 (eq. 17 solved for the distance d) plus the minimum step.
double longest_step(const SamplingPlan& plan, const ResolvedScene& s);

// How many macrocells away a virtual sample's Catmull-Rom window (two steps either side) can
// read, or -1 when more than kMaxVirtualSampleRing: skipping is then not worth its dilation.
constexpr int kMaxVirtualSampleRing = 3;
int virtual_sample_ring(const SamplingPlan& plan, const ResolvedScene& s, int cell_edge);

// The macrocells a ray crosses between t0 and t1, in order, each with the ray parameters where
// the ray enters and leaves it: the GL ray caster's 3D-DDA (Amanatides & Woo), in double.
struct CellCrossing {
  size_t cell = 0;  // MacrocellGrid::index
  double t_in = 0, t_out = 0;
};
std::vector<CellCrossing> cells_along(const MacrocellGrid& grid, const Ray& r, double t0, double t1,
                                      const glm::dvec3& spacing, const glm::dvec3& box_half);

// Adaptive multiplier per macrocell (index as MacrocellGrid::index): M = floor(2 / m + 1),
// m = cell stddev / volume stddev, clamped to [1, kMaxAdaptiveMultiplier]; a constant cell or
// volume (m = 0 or 0 / 0) gets the largest. Depends on the data only, never on the TF.
constexpr int kMaxAdaptiveMultiplier = 8;
std::vector<uint8_t> adaptive_multipliers(const MacrocellGrid& cells, double volume_stddev);
// Standard deviation of the volume's values, from its histogram (bin centres).
double volume_stddev(const Volume& v);

}  // namespace peakcast
