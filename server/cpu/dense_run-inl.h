// The CPU's fast path over runs of lattice points in occupied cells (the hook dense_run of
// shaders/ray/walks.glsl): plain DVR with the ray's colour in locals. Included per SIMD target by
// cpu/ray_kernel.cpp (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_DENSE_RUN_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_DENSE_RUN_INL_H_
#undef PEAKCAST_CPU_DENSE_RUN_INL_H_
#else
#define PEAKCAST_CPU_DENSE_RUN_INL_H_
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <hwy/highway.h>

#include "cpu/ray_caster-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

template <class S>
template <bool kCells>
bool RayCaster<S>::dense_loop(const Lattice& lattice, RayState& st, RayWalk& k, int& index, int& last_visited, int last,
                              vec3 xo, vec3 dv) {
  // Locals: what the loop reads of the references, which the run sampler's stores (floats) could
  // otherwise alias, would be reloaded after every new run; the indices, which through the
  // references were stored and reloaded at every sample (3 of em's 97 instructions per sample).
  const Lattice L = lattice;
  int i = index, visited = last_visited;
  const float stop = st.stop, dvr_weight = st.dvr_weight;
  const bool preint = f_.key.preintegration;
  // The tables and the macrocells, and the current run of samples (field_at's stride-1 case; a
  // run of another stride is sampled anew, to the same values): members that new_run and
  // dense_opacity_slow, being calls, would make the compiler reload at every sample.
  const float* const tf = f_.tf;
  const uint64_t* const tf_bits = f_.tf_alpha_any;
  const uint8_t* const cells = f_.cell_distance;
  const float inv_edge = 1.f / P.cell_edge;
  const ivec3 top = P.cell_grid - 1;
  const float* const run = run_;
  int run_lo = run_first_, run_n = run_stride_ == 1 ? run_count_ : 0;
  vec4 acc = st.acc;
  float samples = st.samples, prev_f = st.prev_f;
  const int first = i;
  bool stopped = false;
  const float dt = lattice_step(L, 0.f, 1.f);  // uniform steps (the ray texture's multiplier in it)
  const bool whole = dt == P.step;             // the table's own step: no correction
  while (i <= last) {
    if constexpr (kCells) {  // walk_leaps's cell test, as it would make it
      const vec3 x = xo + lattice_t(L, float(i)) * dv;
      const vec3 y = x * inv_edge;  // cell_containing and cell_distance, with the grid in locals
      const size_t cell =
          size_t(cell_of(y.x, top.x)) +
          size_t(top.x + 1) * (size_t(cell_of(y.y, top.y)) + size_t(top.y + 1) * size_t(cell_of(y.z, top.z)));
      if (cells[cell] != 0) break;
    }
    float fv;
    if (HWY_LIKELY(unsigned(i - run_lo) < unsigned(run_n))) {
      fv = run[i - run_lo];
    } else {
      fv = new_run(i, 1);
      run_lo = run_first_;
      run_n = run_count_;
    }
    samples += 1.f;
    vec4 s;
    if (preint) {  // the segment from the previous point (visited without a gap)
      if (preint_lookup(r_, prev_f, fv, s)) composite_premultiplied(acc, s, dvr_weight);
    } else if (tf_lookup_in(tf, tf_bits, fv, s) && s.a < 1.f) {
      // (The first point is never in a run; the last one's chord is cut at the exit.) One cold
      // call: more of them made the compiler keep the ray's opacity in memory.
      const float a = HWY_LIKELY(whole && i != last) ? 1.f - s.a : dense_opacity_slow(k, s.a, i, dt);
      composite(acc, vec3(s), a * dvr_weight);
    }
    prev_f = fv;
    visited = i++;
    if (acc.a >= stop) {
      stopped = true;
      break;
    }
  }
  index = i;
  last_visited = visited;
  st.acc = acc;
  st.samples = samples;
  if (i > first) {  // as the last consume leaves them
    st.prev_t = lattice_t(L, float(visited));
    st.prev_f = prev_f;
    k.expect = visited + 1;
  }
  return stopped;
}

template <class S>
bool RayCaster<S>::project_loop(const Lattice& lattice, RayState& st, RayWalk& k, int& index, int& last_visited,
                                int last) {
  const Lattice L = lattice;  // (locals, as dense_loop's: the run sampler's stores cannot alias them)
  RayState s = st;
  int i = index, visited = last_visited;
  const int first = i;
  const float* const run = run_;
  int run_lo = run_first_, run_n = run_stride_ == 1 ? run_count_ : 0;
  bool stopped = false;
  if (i <= last && i != k.expect) s.gap = true;  // as sample_visit marks a gap
  while (i <= last) {
    float fv;
    if (HWY_LIKELY(unsigned(i - run_lo) < unsigned(run_n))) {
      fv = run[i - run_lo];
    } else {
      fv = new_run(i, 1);
      run_lo = run_first_;
      run_n = run_count_;
    }
    s.samples += 1.f;
    float dt = 0.f;                         // (a maximum or minimum reads no chord)
    if (V.projection == kProjectionMean) {  // sample_visit's chord
      dt = lattice_step(L, float(i), 1.f);
      if (i == 0 || i + 1 > k.ray_last) dt = chord_at_ends(dt, i, 1, k.head, k.tail, k.ray_last);
    }
    visited = i++;
    if (project_sample(s, fv, dt)) {
      stopped = true;
      break;
    }
  }
  if (i > first) k.expect = visited + 1;
  st = s;
  index = i;
  last_visited = visited;
  return stopped;
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_DENSE_RUN_INL_H_
