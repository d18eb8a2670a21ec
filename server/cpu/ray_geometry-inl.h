// The ray kernel's per-target geometry (ray_setup.glsl and sampling.glsl in C++): rays, the box
// slab test, the sample lattice, cell indices, the Catmull-Rom spline and 4-lane RGBA lerps.
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
using glm::ivec3;
using glm::vec3;
using glm::vec4;

constexpr int kExtension = 1;  // lattice points visited on each side of an occupied cell's run
constexpr float kHuge = 3.0e38f;
constexpr float kAmbient = 0.3f, kDiffuse = 0.6f, kSpecular = 0.25f, kShininess = 32.0f;

struct Ray {
  vec3 o{0}, d{0};
  float t_eye = 0;
};

struct Lattice {
  float t0 = 0, A = 0, B = 1;
};

float lattice_t(const Lattice& L, float j) { return L.t0 + j * (L.B + L.A * j * 0.5f); }
float lattice_step(const Lattice& L, float j, float m) { return m * (L.B + L.A * (j + 0.5f * m)); }
float lattice_index(const Lattice& L, float t) {
  const float d = std::max(0.f, t - L.t0);
  // A uniform lattice: 2d / (B + sqrt(B^2)) is d / B exactly (sqrt of a rounded square is |B|,
  // and halving is exact), without the square root.
  if (L.A == 0.f) return d / L.B;
  return 2.f * d / (L.B + std::sqrt(L.B * L.B + 2.f * L.A * d));
}
// A float index to int, bounded: a leap far beyond the ray's end stops at `cap`.
int index_floor_cap(float x, int cap) { return x >= float(cap) ? cap : int(x); }
// floor(x) clamped to [0, hi]: what a cell index needs, without floor (a library call or a
// dozen instructions below SSE4.1). Truncation equals floor for x >= 0; x < 0 clamps to 0
// either way; NaN goes to 0 as the clamp of the GL path's int(floor(NaN)) is undefined anyway.
int cell_of(float x, int hi) {
  if (!(x > 0.f)) return 0;
  return x >= float(hi) ? hi : int(x);
}

Ray make_ray(const CpuFrame& f, float px, float py) {
  const float nx = px / float(f.image_w) * 2.f - 1.f;
  const float ny = 1.f - py / float(f.image_h) * 2.f;
  const vec3 lateral = nx * f.half_w * f.right + ny * f.half_h * f.up;
  Ray r;
  if (f.key.orthographic) {
    r.o = f.p0 + lateral;
    r.d = f.forward;
    r.t_eye = -f.dist;
  } else {
    const vec3 d = f.forward + lateral;
    const float len = glm::length(d);
    r.o = f.p0 + f.dist * lateral;
    r.d = d / len;
    r.t_eye = -f.dist * len;
  }
  return r;
}

// Slab test against [-half, half]: (t_enter, t_exit), empty when enter > exit.
void intersect_box(const CpuFrame& f, const Ray& r, float& enter, float& exit_) {
  exit_ = kHuge;
  float tmin_max = -kHuge;
  for (int a = 0; a < 3; ++a) {
    const float d = std::abs(r.d[a]) < 1e-20f ? 1e-20f : r.d[a];
    const float inv = 1.f / d;
    const float t0 = (-f.box_half[a] - r.o[a]) * inv, t1 = (f.box_half[a] - r.o[a]) * inv;
    tmin_max = std::max(tmin_max, std::min(t0, t1));
    exit_ = std::min(exit_, std::max(t0, t1));
  }
  enter = std::max(tmin_max, r.t_eye);
}

Lattice ray_lattice(const CpuFrame& f, const Ray& r, float t_enter) {
  Lattice L;
  L.t0 = t_enter;
  if (f.key.differential) {
    const vec3 d = r.d / glm::dot(r.d, f.forward);                          // depth-1 direction (eq. 7)
    const vec3 u = f.right * (2.f * f.half_w / float(f.image_w));          // one pixel along x
    const float dd = glm::dot(d, d);
    const float dD_dx = glm::length(dd * u - glm::dot(d, u) * d) / (dd * std::sqrt(dd));  // eq. 10
    const float k = f.diff_k;
    const float a = k * dD_dx;
    const float s = std::max(0.f, t_enter - r.t_eye);  // eye -> box entry
    const float x = 2.f * s / (k + std::sqrt(k * k + 2.f * a * s));  // eq. 18, stable form
    L.A = a;
    L.B = std::max(k + a * x, f.min_step);
  } else {
    L.A = 0.f;
    L.B = f.step;
  }
  return L;
}

float catmull_rom(float p0, float p1, float p2, float p3, float s) {
  return 0.5f * (2.f * p1 + (p2 - p0) * s + (2.f * p0 - 5.f * p1 + 4.f * p2 - p3) * s * s +
                 (3.f * p1 - p0 - 3.f * p2 + p3) * s * s * s);
}
vec3 catmull_rom3(vec3 p0, vec3 p1, vec3 p2, vec3 p3, float s) {
  return 0.5f * (2.f * p1 + (p2 - p0) * s + (2.f * p0 - 5.f * p1 + 4.f * p2 - p3) * s * s +
                 (3.f * p1 - p0 - 3.f * p2 + p3) * s * s * s);
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
