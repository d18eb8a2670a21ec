// One ray on the CPU. What it shares with the GL shader (shaders/ray/*.glsl), the walks included,
// is compiled into RayCaster (ray_caster-inl.h); its fast path over dense runs is in
// dense_run-inl.h, the table lookups in ray_tables-inl.h, the geometry helpers in
// ray_geometry-inl.h and the 16-ray leaps in leap_packets-inl.h; this file holds the sample runs,
// the ray's setup and walk, and the entry points. Compiled once per x86 SIMD target (Highway's
// foreach_target) and chosen at run time: the scalar code gains the target's instructions
// (SSE4's floor, AVX's three-operand forms) and calls its own target's run sampler inline.
#include "cpu/ray_kernel.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/ray_texture_mapping.h"
#include "core/transfer_function.h"
#include "render/shader_interface.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "cpu/ray_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "cpu/sampler-inl.h"
#include "cpu/ray_geometry-inl.h"
#include "cpu/leap_packets-inl.h"
#include "cpu/ray_caster-inl.h"
#include "cpu/ray_tables-inl.h"
#include "cpu/dense_run-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

template <class S>
HWY_INLINE float RayCaster<S>::field_at(int i, int m) {
  const int k = i - run_first_;
  if (run_stride_ == 1) {  // the common case, without integer divisions
    if (unsigned(k) < unsigned(run_count_)) return run_[k];
  } else if (run_count_ > 0 && k >= 0 && k % run_stride_ == 0 && k / run_stride_ < run_count_) {
    return run_[k / run_stride_];
  }
  return new_run(i, m);
}

template <class S>
HWY_NOINLINE float RayCaster<S>::new_run(int i, int m) {
  // Runs grow while the ray walks on without a gap, and start at one SIMD vector after one: a
  // leap or the end of an occupied run would waste the rest of a long run, and a vector costs
  // the same however few of its lanes are used.
  const bool continues = run_count_ > 0 && m == run_stride_ && i == run_first_ + run_count_ * run_stride_;
  run_batch_ = continues ? std::min(2 * run_batch_, kMaxRun) : f_.run_lanes;
  SampleRun run;
  run.o = r_.o;
  run.d = r_.d;
  run.half = P.sample_half;
  run.inv_spacing = P.inv_spacing;
  run.t0 = L_.t0;
  run.A = L_.A;
  run.B = L_.B;
  run.first = i;
  run.stride = m;
  run.count = std::clamp((last_ + 1 - i) / m + 1, 1, run_batch_);  // up to last + 1 (vs_finish's extra one)
  Run(f_.voxels, run, run_);
  run_first_ = i;
  run_stride_ = m;
  run_count_ = run.count;
  return run_[0];
}

template <class S>
bool RayCaster<S>::setup(float px, float py) {
  s_.stop = P.stop;
  vec2 span;
  if (!start_ray(vec2(px, py), r_, L_, s_, k_, span, last_)) return false;
  span_x_ = span.x;
  span_y_ = span.y;
  return true;
}

template <class S>
RayResult RayCaster<S>::walk(int first) {
  // One function per walk, each with the shared walk inlined into it (with every walk inlined
  // into one function, the compiler kept vs_push out of line: +8% instructions).
  switch (walk_kind()) {
    case kWalkPoints: walk_as<kWalkPoints>(first); break;
    case kWalkLeaps: walk_as<kWalkLeaps>(first); break;
    default: walk_as<kWalkCells>(first); break;
  }
  return result();
}

template <class S>
void cast_packets(const CpuFrame& f, const float* px, const float* py, int n, RayResult* out) {
  using RayCaster = RayCaster<S>;
  const bool leaps = f.key.space_skipping && !f.key.adaptive;
  for (int k0 = 0; k0 < n; k0 += kRayPacket) {
    const int m = std::min(kRayPacket, n - k0);
    alignas(64) unsigned char storage[kRayPacket][sizeof(RayCaster)];
    RayCaster* rays[kRayPacket];
    LeapInputs in[kRayPacket];
    int first[kRayPacket] = {}, hit_index[kRayPacket];
    bool walks[kRayPacket] = {};
    int hits = 0;
    for (int q = 0; q < m; ++q) {
      rays[q] = new (storage[q]) RayCaster(f);
      if ((walks[q] = rays[q]->setup(px[k0 + q], py[k0 + q]))) {
        if (leaps) in[hits] = rays[q]->leap_inputs();
        hit_index[hits++] = q;
      }
    }
    int firsts[kRayPacket] = {};
    if (leaps && hits > 0) leaps_to_first_occupied(f, in, hits, firsts);
    for (int h = 0; h < hits; ++h) first[hit_index[h]] = firsts[h];
    for (int q = 0; q < m; ++q) {
      out[k0 + q] = walks[q] ? rays[q]->walk(first[q]) : rays[q]->result();  // a miss, or clipped away
      rays[q]->~RayCaster();
    }
  }
}

}  // namespace

// A projection's frame gets the switches read at run time; every other frame the DVR switches,
// with the projection's code folded away.
RayResult CastRay(const CpuFrame& f, float px, float py) {
  if (f.v.projection != 0) return RayCaster<ray::Variant>(f).cast(px, py);
  return RayCaster<DvrSwitches>(f).cast(px, py);
}

void CastRays(const CpuFrame& f, const float* px, const float* py, int n, RayResult* out) {
  if (f.v.projection != 0)
    cast_packets<ray::Variant>(f, px, py, n, out);
  else
    cast_packets<DvrSwitches>(f, px, py, n, out);
}

}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace peakcast::cpu {
HWY_EXPORT(CastRay);
HWY_EXPORT(CastRays);

RayResult cast_ray(const CpuFrame& f, float px, float py) { return HWY_DYNAMIC_DISPATCH(CastRay)(f, px, py); }

void cast_rays(const CpuFrame& f, const float* px, const float* py, int n, RayResult* out) {
  HWY_DYNAMIC_DISPATCH(CastRays)(f, px, py, n, out);
}

}  // namespace peakcast::cpu
#endif
