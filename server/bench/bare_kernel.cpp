// The bare sampling loop on the CPU backend (bare_kernel.h): the ray and lattice of the shared
// ray code (shaders/ray/), the samples from the CPU backend's run sampler, for every x86 SIMD
// target (Highway's foreach_target) as cpu/ray_kernel.cpp is compiled.
#include "bench/bare_kernel.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "bench/bare_kernel.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "cpu/ray_geometry-inl.h"
#include "cpu/sampler-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

class BareRay {
 public:
  explicit BareRay(const CpuFrame& f) : P(f.u), V(f.v), f_(f) {}

  RayResult cast(float px, float py, int budget) {
    const Ray r = make_ray(vec2(px, py));
    const Lattice L = ray_lattice(r, intersect_box(r).x);
    SampleRun run;
    run.o = r.o;
    run.d = r.d;
    run.half = f_.u.sample_half;
    run.inv_spacing = f_.u.inv_spacing;
    run.t0 = L.t0;
    run.A = L.A;
    run.B = L.B;
    float values[kMaxRun];
    float sum = 0.f;
    for (int i = 0; i < budget; i += kMaxRun) {
      run.first = i;
      run.count = std::min(kMaxRun, budget - i);
      Run(f_.voxels, run, values);
      for (int k = 0; k < run.count; ++k) sum += values[k];
    }
    RayResult res;
    res.acc = vec4(sum * 1e-9f);  // keeps the loop from being optimised away
    res.samples = float(budget);
    return res;
  }

 private:
  const ray::RayUniforms& P;
  const ray::Variant V;
  const CpuFrame& f_;
#include "ray/ray_setup.glsl"
#include "ray/lattice.glsl"
};

}  // namespace

RayResult CastRayBare(const CpuFrame& f, float px, float py, int budget) { return BareRay(f).cast(px, py, budget); }

}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace peakcast::cpu {
HWY_EXPORT(CastRayBare);
}  // namespace peakcast::cpu

namespace peakcast::bench {
cpu::RayResult cast_ray_bare(const cpu::CpuFrame& f, float px, float py, int budget) {
  return HWY_DYNAMIC_DISPATCH(cpu::CastRayBare)(f, px, py, budget);
}
}  // namespace peakcast::bench
#endif
