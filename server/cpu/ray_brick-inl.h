// Distributed rendering: the visits a brick holds back before the lattice points it owns
// (visit_behind; docs/distributed.md). Which points it owns is shaders/ray/brick.glsl. Included per SIMD target by cpu/ray_kernel.cpp (Highway's -inl.h
// convention).
#if defined(PEAKCAST_CPU_RAY_BRICK_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_BRICK_INL_H_
#undef PEAKCAST_CPU_RAY_BRICK_INL_H_
#else
#define PEAKCAST_CPU_RAY_BRICK_INL_H_
#endif

#include <algorithm>
#include <cmath>

#include <hwy/highway.h>

#include "core/sampling.h"
#include "cpu/ray_caster-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

// A brick's visit before its points, or its first owned visit with visits held back (see
// behind_): out of line, off the one-process path. True when the ray stopped.
bool RayCaster::visit_behind(int i, int m) {
  if (i < own_first_) {
    behind_[1] = behind_[0];
    behind_m_[1] = behind_m_[0];
    behind_[0] = i;
    behind_m_[0] = m;
    return false;
  }
  const int b0 = behind_[0], b1 = behind_[1];
  behind_[0] = behind_[1] = -1;
  if (b0 + behind_m_[0] == i) {
    if (f_.key.virtual_samples && b1 >= 0 && b1 + behind_m_[1] == b0 && sample_visit(b1, behind_m_[1])) return true;
    if (sample_visit(b0, behind_m_[0])) return true;
  }
  return sample_visit(i, m);
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_BRICK_INL_H_
