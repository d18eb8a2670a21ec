// The ray kernel's per-target helpers outside RayCaster: the ray and lattice types (shared with
// GLSL, shaders/ray/types.glsl), cell indices and 4-lane RGBA lerps.
// Included per SIMD target by cpu/ray_kernel.cpp (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_RAY_GEOMETRY_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_GEOMETRY_INL_H_
#undef PEAKCAST_CPU_RAY_GEOMETRY_INL_H_
#else
#define PEAKCAST_CPU_RAY_GEOMETRY_INL_H_
#endif

#include <hwy/highway.h>

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "cpu/ray_kernel.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;

constexpr float kFar = 3.0e38f;  // ray/ray_setup.glsl kHuge, for the code outside RayCaster

// The ray and its lattice (shaders/ray/types.glsl); the functions on them are RayCaster's.
using namespace peakcast::ray;
#include "ray/types.glsl"

// floor(x) clamped to [0, hi]: what a cell index needs, without floor (a library call or a
// dozen instructions below SSE4.1). Truncation equals floor for x >= 0; x < 0 clamps to 0
// either way; NaN goes to 0 as the clamp of the GL path's int(floor(NaN)) is undefined anyway.
inline int cell_of(float x, int hi) {
  if (!(x > 0.f)) return 0;
  return x >= float(hi) ? hi : int(x);
}

// RGBA texels a + w (b - a) as one 4-lane vector (one lane at a time on the scalar target), no
// fused multiply-add: every target rounds the same.
#if HWY_TARGET == HWY_SCALAR
struct Rgba {
  float v[4];
};
HWY_INLINE Rgba load4(const float* p) { return {{p[0], p[1], p[2], p[3]}}; }
HWY_INLINE Rgba lerp4(Rgba a, Rgba b, float w) {
  for (int k = 0; k < 4; ++k) a.v[k] = a.v[k] + w * (b.v[k] - a.v[k]);
  return a;
}
HWY_INLINE vec4 to_vec4(Rgba a) { return {a.v[0], a.v[1], a.v[2], a.v[3]}; }
#else
using D4 = hn::FixedTag<float, 4>;
HWY_INLINE hn::Vec<D4> load4(const float* p) { return hn::LoadU(D4(), p); }
HWY_INLINE hn::Vec<D4> lerp4(hn::Vec<D4> a, hn::Vec<D4> b, float w) {
  return hn::Add(a, hn::Mul(hn::Set(D4(), w), hn::Sub(b, a)));
}
HWY_INLINE vec4 to_vec4(hn::Vec<D4> v) {
  vec4 out;
  hn::StoreU(v, D4(), &out.x);
  return out;
}
#endif

// What the empty-space leaps of a set-up ray read (walk_leaps's first lines).
struct LeapInputs {
  vec3 xo, dv;
  float t0, A, B, t_limit;
  int last;
};

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_GEOMETRY_INL_H_
