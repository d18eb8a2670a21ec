// Virtual samples for the CPU ray caster (Lee et al. 2010 §3.1, §4): the Catmull-Rom window of
// raycast_body.glsl in C++. Included per SIMD target by cpu/ray_kernel.cpp (Highway's -inl.h
// convention).
#if defined(PEAKCAST_CPU_RAY_VIRTUAL_SAMPLES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_VIRTUAL_SAMPLES_INL_H_
#undef PEAKCAST_CPU_RAY_VIRTUAL_SAMPLES_INL_H_
#else
#define PEAKCAST_CPU_RAY_VIRTUAL_SAMPLES_INL_H_
#endif

#include <hwy/highway.h>

#include "cpu/ray_caster-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

bool RayCaster::vs_segment(float t1, float t2, float dt1, vec4 fw, vec3 g0, vec3 g1, vec3 g2, vec3 g3,
                           float t_limit, bool own) {
  const int vs = f_.key.virtual_samples;
  s_.draw = own;  // the segment's samples are the rank's that owns its first true one (see s_.draw)
  const float k = float(vs);
  const float sub = dt1 / (k + 1.f);
  const float span = t2 - t1;
  // The sub-samples' chords as the true samples' (chord_end()), on the sub-lattice: the ray's first
  // sample stands for half a sub-step, and the last before the exit (t_limit: the ray's last
  // segment) for half a sub-step before it and the rest up to the exit.
  const bool ends = t_limit < kHuge;
  float weight = sub;
  if (t1 == L_.t0) weight -= 0.5f * sub;
  if (ends && t1 + span / (k + 1.f) > t_limit) weight += (t_limit - t1) - 0.5f * sub;
  if (consume(r_, s_, t1, fw.y, g1, weight)) return true;
  for (int q = 1; q <= vs; ++q) {
    const float s = float(q) / (k + 1.f);
    const float t = t1 + s * span;
    if (t > t_limit) break;
    weight = sub;
    if (ends && (q == vs || t1 + float(q + 1) / (k + 1.f) * span > t_limit)) weight += (t_limit - t) - 0.5f * sub;
    const float v = catmull_rom(fw.x, fw.y, fw.z, fw.w, s);
    const vec3 g = catmull_rom3(g0, g1, g2, g3, s);
    if (consume(r_, s_, t, v, g, weight)) return true;
  }
  return false;
}

bool RayCaster::vs_last_segment(float t_limit) {
  const bool prev = w_n_ >= 3;
  return vs_segment(w_t_.z, w_t_.w, w_dt_.z, vec4(prev ? w_f_.y : w_f_.z, w_f_.z, w_f_.w, w_f_.w), prev ? w_g1_ : w_g2_,
                    w_g2_, w_g3_, w_g3_, t_limit, (w_own_ & 2u) != 0);
}

bool RayCaster::vs_flush() {
  bool done = s_.acc.a >= s_.stop;
  if (!done && w_n_ >= 2) done = vs_last_segment(kHuge);
  if (!done && w_n_ >= 1) {
    s_.draw = (w_own_ & 1u) != 0;
    done = consume(r_, s_, w_t_.w, w_f_.w, w_g3_, w_dt_.w);
  }
  w_n_ = 0;
  return done;
}

bool RayCaster::vs_push(float t, float fv, vec3 g, float dt, bool own) {
  w_own_ = ((w_own_ << 1) | (own ? 1u : 0u)) & 15u;
  w_t_ = vec4(w_t_.y, w_t_.z, w_t_.w, t);
  w_f_ = vec4(w_f_.y, w_f_.z, w_f_.w, fv);
  w_dt_ = vec4(w_dt_.y, w_dt_.z, w_dt_.w, dt);
  w_g0_ = w_g1_;
  w_g1_ = w_g2_;
  w_g2_ = w_g3_;
  w_g3_ = g;
  w_n_ = std::min(w_n_ + 1, 4);
  if (w_n_ < 3) return false;
  const bool prev = w_n_ == 4;
  return vs_segment(w_t_.y, w_t_.z, w_dt_.y, vec4(prev ? w_f_.x : w_f_.y, w_f_.y, w_f_.z, w_f_.w), prev ? w_g0_ : w_g1_,
                    w_g1_, w_g2_, w_g3_, kHuge, (w_own_ & 4u) != 0);
}

void RayCaster::vs_finish(int last, float t_exit) {
  if (s_.acc.a >= s_.stop || w_n_ == 0) return;
  if (w_t_.w != lattice_t(L_, float(last))) {  // the ray ended in a skipped cell
    vs_flush();
    return;
  }
  const float t = lattice_t(L_, float(last + 1));
  const float fv = field_at(last + 1, 1);
  s_.samples += 1.f;
  const vec3 g = f_.key.shading ? field_gradient(voxel_coords(r_.o + t * r_.d)) : vec3(0.f);
  if (vs_push(t, fv, g, lattice_step(L_, float(last + 1), 1.f), owned(last + 1))) return;
  vs_last_segment(t_exit);  // the extra sample itself is not composited
  w_n_ = 0;
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_VIRTUAL_SAMPLES_INL_H_
