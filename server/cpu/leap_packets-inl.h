// The empty-space leaps of 16 rays at once (cpu::cast_rays). Included per SIMD target by
// cpu/ray_kernel.cpp after ray_geometry-inl.h (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_LEAP_PACKETS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_LEAP_PACKETS_INL_H_
#undef PEAKCAST_CPU_LEAP_PACKETS_INL_H_
#else
#define PEAKCAST_CPU_LEAP_PACKETS_INL_H_
#endif

#include <hwy/highway.h>

#include "cpu/ray_geometry-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

// walk_leaps's empty-space leaps up to each ray's first occupied lattice point, for a packet of
// rays in SIMD lanes (on sparse scenes most of a ray's leaps come before its first
// occupied cell, and one ray's leaps are a chain of dependent scalar operations). Every lane
// does walk_leaps's arithmetic operation for operation (no fused multiply-add), so each ray
// arrives where its scalar walk would: walk() then goes on from there, its visits unchanged.
void leaps_to_first_occupied(const CpuFrame& f, const LeapInputs* in, int n, int* first) {
  using DF = hn::ScalableTag<float>;
  using DI = hn::RebindToSigned<DF>;
  const DF df;
  const DI di;
  const int N = int(hn::Lanes(df));
  const float edge = f.u.cell_edge, inv_edge = 1.f / f.u.cell_edge;
  const int grid[3] = {f.u.cell_grid[0], f.u.cell_grid[1], f.u.cell_grid[2]};
  const int32_t* table = reinterpret_cast<const int32_t*>(f.cell_distance);  // padded by 3 bytes
  for (int k0 = 0; k0 < n; k0 += N) {
    alignas(64) float xo[3][64], dv[3][64], inv_dv[3][64], ahead[3][64], t0[64], A[64], B[64], lim[64];
    alignas(64) int32_t stp[3][64], last[64], out[64];
    int max_last = 0;
    for (int q = 0; q < N; ++q) {
      const LeapInputs& r = in[std::min(k0 + q, n - 1)];  // spare lanes repeat the last ray
      for (int a = 0; a < 3; ++a) {
        xo[a][q] = r.xo[a];
        dv[a][q] = r.dv[a];
        stp[a][q] = r.dv[a] > 0.f ? 1 : (r.dv[a] < 0.f ? -1 : 0);
        inv_dv[a][q] = std::abs(r.dv[a]) >= 1e-20f ? 1.f / r.dv[a] : 0.f;
        ahead[a][q] = r.dv[a] > 0.f ? 1.f : 0.f;
      }
      t0[q] = r.t0;
      A[q] = r.A;
      B[q] = r.B;
      lim[q] = r.t_limit;
      last[q] = r.last;
      max_last = std::max(max_last, r.last);
    }
    auto i = hn::Zero(di);
    const auto vlast = hn::Load(di, last);
    const auto vlast1 = hn::Add(vlast, hn::Set(di, 1));
    auto active = hn::Lt(i, vlast1);  // i <= last
    const int64_t limit = int64_t(max_last) + 2 + 8 * int64_t(grid[0] + grid[1] + grid[2]) + 4096;
    for (int64_t iter = 0; iter < limit && !hn::AllFalse(di, active); ++iter) {
      const auto fi = hn::ConvertTo(df, i);
      const auto vA = hn::Load(df, A), vB = hn::Load(df, B), vt0 = hn::Load(df, t0);
      // lattice_t: t0 + j (B + A j 0.5)
      const auto t = hn::Add(vt0, hn::Mul(fi, hn::Add(vB, hn::Mul(hn::Mul(vA, fi), hn::Set(df, 0.5f)))));
      hn::Vec<DI> c[3];
      for (int a = 0; a < 3; ++a) {
        const auto x = hn::Add(hn::Load(df, xo[a]), hn::Mul(t, hn::Load(df, dv[a])));
        // cell_of: 0 for x <= 0 or NaN (max returns its second operand then), else min(int(x), hi)
        const auto u =
            hn::Min(hn::Max(hn::Mul(x, hn::Set(df, inv_edge)), hn::Zero(df)), hn::Set(df, float(grid[a] - 1)));
        c[a] = hn::ConvertTo(di, u);
      }
      const auto index =
          hn::Add(c[0], hn::Mul(hn::Set(di, grid[0]), hn::Add(c[1], hn::Mul(hn::Set(di, grid[1]), c[2]))));
      const auto d = hn::And(hn::GatherOffset(di, table, index), hn::Set(di, 0xFF));
      const auto empty = hn::And(active, hn::RebindMask(di, hn::Ne(d, hn::Zero(di))));
      const auto reach = hn::Sub(d, hn::Set(di, 1));
      auto t_leave = hn::Set(df, kFar);
      for (int a = 0; a < 3; ++a) {
        const auto face =
            hn::Add(hn::ConvertTo(df, hn::Add(c[a], hn::Mul(hn::Load(di, stp[a]), reach))), hn::Load(df, ahead[a]));
        const auto ta =
            hn::Mul(hn::Sub(hn::Mul(face, hn::Set(df, edge)), hn::Load(df, xo[a])), hn::Load(df, inv_dv[a]));
        const auto moves = hn::Ge(hn::Abs(hn::Load(df, dv[a])), hn::Set(df, 1e-20f));
        t_leave = hn::IfThenElse(moves, hn::Min(t_leave, ta), t_leave);
      }
      // lattice_index(min(t_leave, t_limit)): d / B on a uniform lattice, else the stable form
      const auto dd = hn::Max(hn::Zero(df), hn::Sub(hn::Min(t_leave, hn::Load(df, lim)), vt0));
      const auto general =
          hn::Div(hn::Mul(hn::Set(df, 2.f), dd),
                  hn::Add(vB, hn::Sqrt(hn::Add(hn::Mul(vB, vB), hn::Mul(hn::Mul(hn::Set(df, 2.f), vA), dd)))));
      const auto idx = hn::IfThenElse(hn::Eq(vA, hn::Zero(df)), hn::Div(dd, vB), general);
      const auto next = hn::Ceil(idx);
      const auto cap = hn::Add(vlast, hn::Set(di, 1));
      // index_at_most (ray/walks.glsl): next >= cap ? cap : int(next)
      const auto capped = hn::IfThenElse(hn::RebindMask(di, hn::Ge(next, hn::ConvertTo(df, cap))), cap,
                                         hn::ConvertTo(di, hn::Min(next, hn::ConvertTo(df, cap))));
      const auto leapt = hn::Max(hn::Add(i, hn::Set(di, 1)), capped);
      i = hn::IfThenElse(empty, leapt, i);
      active = hn::And(empty, hn::Lt(i, vlast1));
    }
    hn::Store(i, di, out);
    for (int q = 0; q < N && k0 + q < n; ++q) first[k0 + q] = out[q];
  }
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_LEAP_PACKETS_INL_H_
