// Distributed rendering's clipping of one ray to the lattice points its brick owns
// (RayCaster::owns), and the visits it holds back before them (visit_behind;
// docs/distributed.md). Included per SIMD target by cpu/ray_kernel.cpp (Highway's -inl.h
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

bool RayCaster::clip_to_brick() {
  // A first guess from the ray's parameter interval in the own box (world coordinates), then
  // owns() decides at both ends, moving them until they agree with it: the owned points are
  // consecutive (the box is convex and the points' coordinates are monotone along the ray),
  // and the guess may be off by more than a point where the ray is nearly parallel to a face.
  // Axes the ray does not move along, and faces on the volume's own faces, do not bound it.
  if (last_ < 0) return false;
  const vec3 lo = f_.own_lo * f_.spacing - f_.box_half, hi = f_.own_hi * f_.spacing - f_.box_half;
  float t_in = -kHuge, t_out = kHuge;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(r_.d[a]) < 1e-20f) continue;
    const float t_lo = f_.at_start[a] ? (r_.d[a] > 0.f ? -kHuge : kHuge) : (lo[a] - r_.o[a]) / r_.d[a];
    const float t_hi = f_.at_end[a] ? (r_.d[a] > 0.f ? kHuge : -kHuge) : (hi[a] - r_.o[a]) / r_.d[a];
    t_in = std::max(t_in, std::min(t_lo, t_hi));
    t_out = std::min(t_out, std::max(t_lo, t_hi));
  }
  if (!(t_in <= t_out)) t_in = t_out = 0.5f * (std::max(t_in, span_x_) + std::min(t_out, span_y_));
  auto index_near = [&](float t) {
    const float i = std::round(lattice_index(L_, std::clamp(t, span_x_, span_y_)));
    return i <= 0.f || !(i == i) ? 0 : index_floor_cap(i, last_);
  };
  int first = index_near(t_in), last = std::max(first, index_near(t_out));
  while (first <= last && !owns(first)) ++first;
  while (last >= first && !owns(last)) --last;
  if (first > last) return false;
  while (first > 0 && owns(first - 1)) --first;
  while (last < last_ && owns(last + 1)) ++last;
  own_first_ = first;
  own_last_ = last;
  // Virtual samples: the two visits after the last owned point (the Catmull-Rom window of the
  // last owned segment), and one more, so that whether the second is visited is decided as in
  // one process (a run of occupied cells starting there visits the point before it). Adaptive
  // sampling: each visit is up to kMaxAdaptiveMultiplier points on, and the last owned visit's
  // step (its multiplier, cut at its cell's last point) is decided as in one process only when
  // the walk goes on past it. (The segment out of the last owned point is drawn by the rank
  // owning its end, see draw_.)
  const int m = f_.key.adaptive ? kMaxAdaptiveMultiplier : 1;
  const int beyond = f_.key.virtual_samples ? 2 * m + 1 : (f_.key.adaptive ? m : 0);
  last_ = int(std::min<int64_t>(int64_t(last) + beyond, last_));
  return true;
}

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
