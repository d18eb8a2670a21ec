// The CPU ray caster's table lookups (tf.glsl, preintegration.glsl): the TF table at a sample,
// the exact TF at a peak, the preintegration table for a segment; the first and last read the
// table bits (table_bits.h) before the table. Included per SIMD target by cpu/ray_kernel.cpp
// (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_RAY_TABLES_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_TABLES_INL_H_
#undef PEAKCAST_CPU_RAY_TABLES_INL_H_
#else
#define PEAKCAST_CPU_RAY_TABLES_INL_H_
#endif

#include <algorithm>
#include <cmath>

#include <hwy/highway.h>

#include "cpu/ray_caster-inl.h"
#include "cpu/table_bits.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

template <class S>
HWY_INLINE bool RayCaster<S>::tf_lookup(float s, vec4& out) const {
  return tf_lookup_in(f_.tf, f_.tf_alpha_any, s, out);
}

template <class S>
HWY_INLINE bool RayCaster<S>::tf_lookup_in(const float* tf, const uint64_t* bits, float s, vec4& out) {
  // GL_LINEAR between texel centres of an n-entry table, clamped: texel space u = s (n - 1).
  const int size = TransferFunction::kTableSize;
  const float u = std::clamp(s, 0.f, 1.f) * float(size - 1);
  const int i = std::min(int(u), size - 2);
  if (!test_bit(bits, size_t(i))) return false;  // both texels transparent
  const float* a = tf + 4 * i;
  out = to_vec4(lerp4(load4(a), load4(a + 4), u - float(i)));
  return true;
}

template <class S>
HWY_INLINE bool RayCaster<S>::preint_lookup(const Ray&, float s_front, float s_back, vec4& out) const {
  const int n = P.preint_size;
  const float u = std::clamp(s_front, 0.f, 1.f) * float(n - 1), v = std::clamp(s_back, 0.f, 1.f) * float(n - 1);
  const int i = std::min(int(u), n - 2), j = std::min(int(v), n - 2);
  if (!test_bit(f_.preint_any, size_t(j) * size_t(n - 1) + size_t(i))) return false;  // zeros only
  const float wu = u - float(i), wv = v - float(j);
  const float* row0 = f_.preint + (size_t(j) * size_t(n) + size_t(i)) * 4;
  const float* row1 = row0 + size_t(n) * 4;
  const auto c0 = lerp4(load4(row0), load4(row0 + 4), wu);
  const auto c1 = lerp4(load4(row1), load4(row1 + 4), wu);
  out = to_vec4(lerp4(c0, c1, wv));
  return true;
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_TABLES_INL_H_
