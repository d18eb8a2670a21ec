// sample_run and the SIMD target's name: the per-target sampler (sampler-inl.h) compiled for
// every x86 target and chosen at run time. The ray kernel includes the same header and calls
// its own target's copy directly.
#include "cpu/sampler.h"

#include <algorithm>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "cpu/sampler_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "cpu/sampler-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
const char* Target() { return hwy::TargetName(HWY_TARGET); }
void RunExported(const VoxelGrid& g, const SampleRun& r, float* out) { Run(g, r, out); }
int Lanes() { return int(hwy::HWY_NAMESPACE::Lanes(hwy::HWY_NAMESPACE::ScalableTag<float>())); }
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace peakcast::cpu {
HWY_EXPORT(RunExported);
HWY_EXPORT(Target);
HWY_EXPORT(Lanes);

void sample_run(const VoxelGrid& g, const SampleRun& r, float* out) { HWY_DYNAMIC_DISPATCH(RunExported)(g, r, out); }

const char* simd_target() { return HWY_DYNAMIC_DISPATCH(Target)(); }
int sample_run_lanes() { return std::min(HWY_DYNAMIC_DISPATCH(Lanes)(), kMaxRun); }

}  // namespace peakcast::cpu
#endif
