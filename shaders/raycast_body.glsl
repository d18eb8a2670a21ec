// The ray caster shared by the fragment and compute entry points (raycast.frag, raycast.comp).
// Classification: post (TF table per sample), peaks (PEAKS: Knoll's peak finding between
// samples, with PEAK_XOR / PEAKS_ONLY modes) or pre-integrated segments (PREINTEGRATION).
// Samples lie on the ray's lattice (ray/lattice.glsl: uniform or DIFFERENTIAL), indices
// 0..lattice_index(t_exit), computed from the index (no accumulated t += dt drift). Space
// skipping visits only the lattice points inside occupied macrocells, so it changes no sample
// that contributes; ADAPTIVE visits only the multiples of each cell's multiplier.

#include "sampling.glsl"

#ifdef SPACE_SKIPPING
// Per macrocell, the Chebyshev distance in cells to the nearest occupied one (0: occupied).
layout(std430, binding = SSBO_CELL_DISTANCE) readonly buffer CellDistance { uint u_cell_distance[]; };
#endif

// Peak finding and preintegration are declared in every variant (the shared consume names them;
// a variant without them folds the calls away and the compiler drops what they bind).
#include "peak_find.glsl"
#include "preintegration.glsl"
#include "ray/projection.glsl"
#include "ray/consume.glsl"


// The field at lattice point i (the target's hook of ray/virtual_samples.glsl vs_finish).
float lattice_field(Ray r, Lattice L, int i, int m) { return sample_field(r, voxel_at(r, lattice_t(L, float(i)))); }
#include "ray/virtual_samples.glsl"
#include "ray/visit.glsl"

// The walks' hooks (ray/walks.glsl): the macrocell tables, the cell of a point, and no fast path.
// Per macrocell, its values' (min, max) in TF coordinates: what a maximum or minimum projection
// skips by (ray/projection.glsl projection_skips).
#ifdef PROJECTION
#if PROJECTION != 3 && !defined(VIRTUAL_SAMPLES)
#define CELL_RANGES
layout(std430, binding = SSBO_CELL_RANGE) readonly buffer CellRange { vec2 u_cell_range[]; };
#endif
#endif
vec2 cell_range(ivec3 c) {
#ifdef CELL_RANGES
  return u_cell_range[cell_index(c)];
#else
  return vec2(0.0, 1.0);
#endif
}
uint cell_distance(ivec3 c) {
#ifdef SPACE_SKIPPING
  return cell_byte(u_cell_distance, c);
#else
  return 0u;
#endif
}
int cell_multiplier(ivec3 c) {
#ifdef ADAPTIVE
  // The clamp also matters to llvmpipe: with the raw byte as the loop increment it rendered
  // adaptive frames wrong (a constant volume at 31.9 dB; the bytes were right).
  return clamp(int(cell_byte(u_cell_stride, c)), 1, 8);
#else
  return 1;
#endif
}
// Clamped in float before the conversion, as the CPU's cell_of: a point far outside the grid
// never converts to an integer out of int's range (undefined in GLSL).
ivec3 cell_containing(vec3 x) { return ivec3(clamp(floor(x), vec3(0.0), vec3(P.cell_grid - 1))); }
bool dense_run(Ray r, Lattice L, inout RayState s, inout RayWalk k, inout int i, inout int visited, int last, bool cells,
               vec3 xo, vec3 dv) {
  return false;
}
#include "ray/walks.glsl"
#include "ray_texture.glsl"
#include "ray/ray_start.glsl"

RayState cast_ray(vec2 pixel) {
  RayState res = RayState(vec4(0.0), 0.0, P.stop, 1.0, 1.0, true, 0.0, 0.0, false, false, 0.0, 0.0);
  SampleWindow window;  // virtual samples (n counts the samples it holds; the rest is never read)
  window.n = 0;
  window.own = 0u;
  Ray r;
  Lattice L;
  RayWalk walk;
  vec2 span;
  int last;
  if (start_ray(pixel, r, L, res, walk, span, last)) walk_ray(r, L, res, walk, window, last, span, 0, walk_kind());
  return res;
}

