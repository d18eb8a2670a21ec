// The bare sampling loop on the CPU backend: the ceiling peakcast-bench measures the ray caster
// against (bare_sampling.h).
#pragma once

#include "cpu/ray_kernel.h"

namespace peakcast::bench {

// The ray through pixel centre (px, py): its first `budget` lattice points, reconstructed by the
// CPU backend's SIMD sampler and summed, nothing classified or composited. Compiled per SIMD
// target, as the ray kernel is, and dispatched to the same one.
cpu::RayResult cast_ray_bare(const cpu::CpuFrame& f, float px, float py, int budget);

}  // namespace peakcast::bench
