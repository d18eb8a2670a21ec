// The per-target part of the CPU sampler (Highway's -inl.h convention: included once per SIMD
// target by foreach_target.h in the files that use it, sampler_simd.cpp and ray_kernel.cpp, so
// the ray kernel calls the run sampler of its own target inline). A run's lanes are consecutive
// points of one ray, not one point of many rays: a run never diverges (every lane samples),
// where a packet of rays would (leaps, early termination). The arithmetic is sampler.h's,
// operation for operation, so a run's values equal sample_field's at the same points.
// NOLINT(build/include_guard): toggled per target, as Highway's -inl.h headers are.
#if defined(PEAKCAST_CPU_SAMPLER_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_SAMPLER_INL_H_
#undef PEAKCAST_CPU_SAMPLER_INL_H_
#else
#define PEAKCAST_CPU_SAMPLER_INL_H_
#endif

#include <hwy/highway.h>

#include "cpu/sampler.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using DF = hn::ScalableTag<float>;
using DI = hn::RebindToSigned<DF>;
using VF = hn::Vec<DF>;
using VI = hn::Vec<DI>;

// Trilinear in stored units at (x, y, z), positions in voxel coordinates (sampler.h).
template <VoxelType kType, class D = DF, class V = hn::Vec<D>>
HWY_INLINE V Trilinear(const VoxelGrid& g, V x, V y, V z) {
  using DIx = hn::RebindToSigned<D>;
  using VIx = hn::Vec<DIx>;
  const D df;
  const DIx di;
  V f[3];
  VIx i[3];
  const V p[3] = {x, y, z};
  for (int a = 0; a < 3; ++a) {
    // max first: NaN lanes become 0, as fmax does in the scalar sampler.
    const V c = hn::Min(hn::Max(p[a], hn::Zero(df)), hn::Set(df, g.hi[a]));
    i[a] = hn::Min(hn::ConvertTo(di, c), hn::Set(di, g.base_max[a]));
    f[a] = hn::Sub(c, hn::ConvertTo(df, i[a]));
  }
  const VIx o = hn::Add(
      i[0], hn::Add(hn::Mul(i[1], hn::Set(di, int32_t(g.stride_y))), hn::Mul(i[2], hn::Set(di, int32_t(g.stride_z)))));
  const VIx oy = hn::Set(di, int32_t(g.next_y)), oz = hn::Set(di, int32_t(g.next_z));
  const VIx offs[4] = {o, hn::Add(o, oy), hn::Add(o, oz), hn::Add(o, hn::Add(oy, oz))};
  V rows[4];
  for (int k = 0; k < 4; ++k) {
    V a, b;
    if constexpr (kType == VoxelType::F32) {
      const float* base = reinterpret_cast<const float*>(g.data);
      a = hn::GatherIndex(df, base, offs[k]);
      b = hn::GatherIndex(df, base, hn::Add(offs[k], hn::Set(di, g.n[0] > 1 ? 1 : 0)));
    } else {
      // One 32-bit load per lane holds the voxel and its +x neighbour (the bytes after the
      // volume's last voxel are Volume::kTailPadding).
      const int32_t* base = reinterpret_cast<const int32_t*>(g.data);
      if constexpr (kType == VoxelType::U8) {
        const VIx w = hn::GatherOffset(di, base, offs[k]);
        a = hn::ConvertTo(df, hn::And(w, hn::Set(di, 0xFF)));
        b = hn::ConvertTo(df, hn::And(hn::ShiftRight<8>(w), hn::Set(di, 0xFF)));
      } else {
        const VIx w = hn::GatherOffset(di, base, hn::Add(offs[k], offs[k]));
        a = hn::ConvertTo(df, hn::And(w, hn::Set(di, 0xFFFF)));
        b = hn::ConvertTo(df, hn::And(hn::ShiftRight<16>(w), hn::Set(di, 0xFFFF)));
      }
      if (g.n[0] == 1) b = a;
    }
    rows[k] = hn::Add(a, hn::Mul(f[0], hn::Sub(b, a)));
  }
  const V c0 = hn::Add(rows[0], hn::Mul(f[1], hn::Sub(rows[1], rows[0])));
  const V c1 = hn::Add(rows[2], hn::Mul(f[1], hn::Sub(rows[3], rows[2])));
  return hn::Add(c0, hn::Mul(f[2], hn::Sub(c1, c0)));
}

template <VoxelType kType>
HWY_INLINE VF Tricubic(const VoxelGrid& g, VF x, VF y, VF z) {
  const DF df;
  const VF p[3] = {x, y, z};
  VF g0[3], g1[3], h0[3], h1[3];
  const VF one = hn::Set(df, 1.f), three = hn::Set(df, 3.f), six = hn::Set(df, 6.f);
  for (int a = 0; a < 3; ++a) {
    const VF i = hn::Floor(p[a]), f = hn::Sub(p[a], i);
    const VF f2 = hn::Mul(f, f), f3 = hn::Mul(f2, f);
    const VF w0 = hn::Div(hn::Sub(hn::Add(hn::Sub(one, hn::Mul(three, f)), hn::Mul(three, f2)), f3), six);
    const VF w1 = hn::Div(hn::Add(hn::Sub(hn::Set(df, 4.f), hn::Mul(hn::Set(df, 6.f), f2)), hn::Mul(three, f3)), six);
    const VF w2 =
        hn::Div(hn::Sub(hn::Add(hn::Add(one, hn::Mul(three, f)), hn::Mul(three, f2)), hn::Mul(three, f3)), six);
    const VF w3 = hn::Div(f3, six);
    g0[a] = hn::Add(w0, w1);
    g1[a] = hn::Add(w2, w3);
    h0[a] = hn::Add(hn::Sub(i, one), hn::Div(w1, g0[a]));
    h1[a] = hn::Add(hn::Add(i, one), hn::Div(w3, g1[a]));
  }
  const VF v000 = Trilinear<kType>(g, h0[0], h0[1], h0[2]), v100 = Trilinear<kType>(g, h1[0], h0[1], h0[2]);
  const VF v010 = Trilinear<kType>(g, h0[0], h1[1], h0[2]), v110 = Trilinear<kType>(g, h1[0], h1[1], h0[2]);
  const VF v001 = Trilinear<kType>(g, h0[0], h0[1], h1[2]), v101 = Trilinear<kType>(g, h1[0], h0[1], h1[2]);
  const VF v011 = Trilinear<kType>(g, h0[0], h1[1], h1[2]), v111 = Trilinear<kType>(g, h1[0], h1[1], h1[2]);
  auto pair = [](VF wa, VF a, VF wb, VF b) { return hn::Add(hn::Mul(wa, a), hn::Mul(wb, b)); };
  const VF z0 = pair(g0[1], pair(g0[0], v000, g1[0], v100), g1[1], pair(g0[0], v010, g1[0], v110));
  const VF z1 = pair(g0[1], pair(g0[0], v001, g1[0], v101), g1[1], pair(g0[0], v011, g1[0], v111));
  return pair(g0[2], z0, g1[2], z1);
}

template <VoxelType kType, bool kTricubic, class D = DF>
void RunT(const VoxelGrid& g, const SampleRun& r, float* HWY_RESTRICT out) {
  using VF = hn::Vec<D>;
  const D df;
  const size_t N = hn::Lanes(df);
  alignas(64) float tail[kMaxRun + 64];
  for (int k = 0; k < r.count; k += int(N)) {
    // j = first + (k + lane) * stride, exact in float below 2^24 (kMaxSamplesPerRay is 2^20).
    const VF j = hn::Add(hn::Set(df, float(r.first)),
                         hn::Mul(hn::Add(hn::Set(df, float(k)), hn::Iota(df, 0.f)), hn::Set(df, float(r.stride))));
    // t = t0 + j * (B + A * j * 0.5), then ((o + t d) + half) * inv_spacing, as shaders/ray/ray_setup.glsl.
    const VF t =
        hn::Add(hn::Set(df, r.t0),
                hn::Mul(j, hn::Add(hn::Set(df, r.B), hn::Mul(hn::Mul(hn::Set(df, r.A), j), hn::Set(df, 0.5f)))));
    VF p[3];
    for (int a = 0; a < 3; ++a)
      p[a] = hn::Mul(hn::Add(hn::Add(hn::Set(df, r.o[a]), hn::Mul(t, hn::Set(df, r.d[a]))), hn::Set(df, r.half[a])),
                     hn::Set(df, r.inv_spacing[a]));
    VF v;
    if constexpr (kTricubic) {
      v = Tricubic<kType>(g, p[0], p[1], p[2]);
    } else {
      v = Trilinear<kType, D>(g, p[0], p[1], p[2]);
    }
    v = hn::Add(hn::Mul(v, hn::Set(df, g.scale)), hn::Set(df, g.bias));
    if (k + int(N) <= r.count) {
      hn::StoreU(v, df, out + k);
    } else {
      hn::Store(v, df, tail);
      for (int q = 0; k + q < r.count; ++q) out[k + q] = tail[q];
    }
  }
}

HWY_INLINE void Run(const VoxelGrid& g, const SampleRun& r, float* HWY_RESTRICT out) {
  if (!g.simd_offsets) {  // offsets beyond 32 bits: one point at a time
    for (int k = 0; k < r.count; ++k) {
      const float j = float(r.first) + float(k) * float(r.stride);
      const float t = r.t0 + j * (r.B + r.A * j * 0.5f);
      out[k] = sample_field(g, ((r.o + t * r.d) + r.half) * r.inv_spacing);
    }
    return;
  }
#if HWY_TARGET != HWY_SCALAR
  // A short run on a target wider than 8 lanes: 8-lane vectors (gathers cost per lane).
  using D8 = hn::CappedTag<float, 8>;
  if (!g.tricubic && r.count <= 8 && hn::Lanes(DF()) > 8) {
    switch (g.type) {
      case VoxelType::U8: return RunT<VoxelType::U8, false, D8>(g, r, out);
      case VoxelType::U16: return RunT<VoxelType::U16, false, D8>(g, r, out);
      case VoxelType::F32: return RunT<VoxelType::F32, false, D8>(g, r, out);
    }
  }
#endif
  switch (g.type) {
    case VoxelType::U8:
      return g.tricubic ? RunT<VoxelType::U8, true>(g, r, out) : RunT<VoxelType::U8, false>(g, r, out);
    case VoxelType::U16:
      return g.tricubic ? RunT<VoxelType::U16, true>(g, r, out) : RunT<VoxelType::U16, false>(g, r, out);
    case VoxelType::F32:
      return g.tricubic ? RunT<VoxelType::F32, true>(g, r, out) : RunT<VoxelType::F32, false>(g, r, out);
  }
}

// The tricubic point, kept out of line: inlined into SamplePoint (as the compiler chose once the
// translation unit left it room) it made every trilinear call dearer (SamplePoint +12%, a
// peaks-shaded frame +1.8% instructions).
HWY_NOINLINE inline float SampleTricubicPoint(const VoxelGrid& g, const glm::vec3& x) { return sample_field(g, x); }

// sample_field (sampler.h) at one point, compiled for this target: root solving and gradients
// call it point by point. The same arithmetic, so the same values.
inline float SamplePoint(const VoxelGrid& g, const glm::vec3& x) {
  if (g.tricubic) return SampleTricubicPoint(g, x);
  float raw = 0.f;
  switch (g.type) {
    case VoxelType::U8: raw = trilinear_typed<uint8_t>(g, x.x, x.y, x.z); break;
    case VoxelType::U16: raw = trilinear_typed<uint16_t>(g, x.x, x.y, x.z); break;
    case VoxelType::F32: raw = trilinear_typed<float>(g, x.x, x.y, x.z); break;
  }
  return raw * g.scale + g.bias;
}

// SamplePoint at p + 1 and p - 1 on each axis (+x, -x, +y, -y, +z, -z): a trilinear gradient's
// six samples, bit for bit SamplePoint's, with what they share computed once.
inline void SampleCross(const VoxelGrid& g, const glm::vec3& p, float out[6]) {
  if (g.tricubic) {
    for (int a = 0; a < 3; ++a) {
      glm::vec3 e(0.f);
      e[a] = 1.f;
      out[2 * a] = SampleTricubicPoint(g, p + e);
      out[2 * a + 1] = SampleTricubicPoint(g, p - e);
    }
    return;
  }
  switch (g.type) {
    case VoxelType::U8: trilinear_cross<uint8_t>(g, p, out); break;
    case VoxelType::U16: trilinear_cross<uint16_t>(g, p, out); break;
    case VoxelType::F32: trilinear_cross<float>(g, p, out); break;
  }
  for (int k = 0; k < 6; ++k) out[k] = out[k] * g.scale + g.bias;
}

}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_SAMPLER_INL_H_
