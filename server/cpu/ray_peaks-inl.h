// Peak finding between samples for the CPU ray caster (Knoll et al. 2009 §4.2, Algorithm 1,
// errata in docs/architecture.md): shaders/peak_find.glsl in C++. Included per SIMD target by
// cpu/ray_kernel.cpp (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_RAY_PEAKS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_PEAKS_INL_H_
#undef PEAKCAST_CPU_RAY_PEAKS_INL_H_
#else
#define PEAKCAST_CPU_RAY_PEAKS_INL_H_
#endif

#include <hwy/highway.h>

#include "cpu/ray_caster-inl.h"
#include "cpu/table_bits.h"
#include "render/shader_interface.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

// Knoll et al. 2009 Algorithm 1 with the errata (peak_find.glsl).
bool RayCaster::find_peaks(float t0, float f0, float t1, float f1) {
  const int bins = P.peak_bins;
  const int i = peak_bin(f0), j = peak_bin(f1);
  if (!test_bit(f_.peak_any, size_t(j) * size_t(bins) + size_t(i))) return false;  // an empty texel
  const bool reverse = (i == j) && f0 > f1;  // the diagonal is stored ascending
  const int max_peaks = P.max_peaks;
  float found[4];
  int n = 0;
  bool done = false;
  for (int layer = 0; layer < P.peak_layers && !done; ++layer) {
    const float* slots = f_.peak_texels + ((size_t(layer) * bins + size_t(j)) * bins + size_t(i)) * 4;
    for (int s = 0; s < 4; ++s) {
      const float v = slots[s];
      if (v == render::kNoPeakTexel) {
        done = true;
        break;
      }
      if (!crosses(f0, f1, v)) continue;
      if (reverse) {  // keep the last four in table order: the first four along the ray
        if (n == 4) {
          found[0] = found[1];
          found[1] = found[2];
          found[2] = found[3];
          n = 3;
        }
        found[n++] = v;
      } else {
        found[n++] = v;
        if (n == max_peaks) {
          done = true;
          break;
        }
      }
    }
  }
  const int count = std::min(n, max_peaks);
  if (!draw_) return count > 0;  // another brick's consume (see draw_): whether it holds a peak only
  for (int k = 0; k < count; ++k) {
    const float v = reverse ? found[n - 1 - k] : found[k];
    const vec4 c = tf_exact(v);
    vec3 rgb(c);
    if (f_.key.shading) {
      const float t = solve_root(r_, t0, f0, t1, f1, v, res_.samples);
      rgb = shade(rgb, field_gradient(voxel_coords(r_.o + t * r_.d)), r_.d);
    } else {
      res_.samples += root_evaluations(f0, f1, v);
    }
    composite(res_.acc, rgb, c.a * peak_weight_);  // unscaled opacity at the peak (Knoll §4.2)
    if (res_.acc.a >= stop_) break;
  }
  return count > 0;
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_PEAKS_INL_H_
