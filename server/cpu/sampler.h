// Field reconstruction for the CPU backend (the twin of shaders/common_sampling.glsl): trilinear
// with GL's clamp-to-edge, and the cubic B-spline from eight trilinear fetches (Sigg & Hadwiger
// 2005). Positions in voxel coordinates (voxel i at i), values in TF coordinates.
//
// One point at a time (sample_field: root solving, gradients) or a run of lattice points along
// a ray at once (sample_run, SIMD through Highway: sampler_simd.cpp): the ray caster's samples.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <glm/vec3.hpp>

#include "core/volume.h"

namespace peakcast::cpu {

// The voxels as the sampler reads them: as stored (mapped by scale and bias per sample), or a
// float volume's copy in TF coordinates (CpuVolume::floats_in_place). At least Volume::kTailPadding readable bytes
// follow the last voxel.
struct VoxelGrid {
  const uint8_t* data = nullptr;
  VoxelType type = VoxelType::U8;
  int64_t n[3] = {1, 1, 1};
  int64_t stride_y = 1, stride_z = 1;  // in voxels
  int64_t next_y = 0, next_z = 0;      // the +1 neighbour's offset (0 on an axis of one voxel)
  float hi[3] = {0, 0, 0};             // n - 1: positions are clamped to [0, hi]
  int32_t base_max[3] = {0, 0, 0};     // the lower corner's largest index, max(n - 2, 0)
  float scale = 1.f, bias = 0.f;       // stored value -> TF coordinate
  bool tricubic = false;
  bool simd_offsets = true;  // byte offsets fit the SIMD gathers' 32-bit lanes

  template <class T>
  float at(int64_t i) const {
    T v;
    std::memcpy(&v, data + size_t(i) * sizeof(T), sizeof(T));
    return float(v);
  }
  float voxel(int64_t i) const {
    switch (type) {
      case VoxelType::U8: return float(data[i]);
      case VoxelType::U16: return at<uint16_t>(i);
      case VoxelType::F32: return at<float>(i);
    }
    return 0.f;
  }
};

// Makes the grid of `data` laid out like `v` (x fastest).
VoxelGrid make_voxel_grid(const Volume& v, const uint8_t* data, VoxelType type, float scale, float bias, bool tricubic);

// One axis of a trilinear lookup: the lower corner's index and the weight of the upper one.
struct TrilinearAxis {
  int32_t i;
  float f;
};

// Coordinate p on axis a clamped to [0, hi] (GL_CLAMP_TO_EDGE), its corner and weight.
[[gnu::always_inline]] inline TrilinearAxis trilinear_axis(const VoxelGrid& g, float p, int a) {
  // fmin(fmax(p, 0), hi) without libm's calls: NaN -> 0 (the comparison is false).
  const float lo = p > 0.f ? p : 0.f;
  const float c = lo < g.hi[a] ? lo : g.hi[a];
  const int32_t i = std::min(int32_t(c), g.base_max[a]);
  return {i, c - float(i)};
}

// The trilinear blend of the eight voxels around the corner (x.i, y.i, z.i), for voxels of type T.
template <class T>
[[gnu::always_inline]] inline float trilinear_blend(const VoxelGrid& g, TrilinearAxis x, TrilinearAxis y,
                                                    TrilinearAxis z) {
  const int64_t o = x.i + y.i * g.stride_y + z.i * g.stride_z;
  const int64_t nx = g.n[0] > 1 ? 1 : 0;
  auto row = [&](int64_t at) {
    const float a = g.at<T>(at), b = g.at<T>(at + nx);
    return a + x.f * (b - a);
  };
  const float c00 = row(o), c10 = row(o + g.next_y), c01 = row(o + g.next_z), c11 = row(o + g.next_y + g.next_z);
  const float c0 = c00 + y.f * (c10 - c00), c1 = c01 + y.f * (c11 - c01);
  return c0 + z.f * (c1 - c0);
}

// Trilinear in stored units (GL_LINEAR, GL_CLAMP_TO_EDGE on every axis), for voxels of type T.
// Always inlined: the per-target ray kernel's point sampler (sampler-inl.h's SamplePoint) then
// gets its target's instructions, where an out-of-line copy would link as the baseline's.
template <class T>
[[gnu::always_inline]] inline float trilinear_typed(const VoxelGrid& g, float x, float y, float z) {
  return trilinear_blend<T>(g, trilinear_axis(g, x, 0), trilinear_axis(g, y, 1), trilinear_axis(g, z, 2));
}

// The six samples of a central difference, at p + 1 and p - 1 on each axis (in that order, x
// first), as trilinear_typed gives each (the same arithmetic, bit for bit): the axes a sample
// keeps at p are clamped and split once for all of them.
template <class T>
[[gnu::always_inline]] inline void trilinear_cross(const VoxelGrid& g, const glm::vec3& p, float out[6]) {
  // Written out axis by axis: a loop over the axes with an indexed copy of the three kept the
  // copies in memory (a peaks-shaded frame stored 12% more; docs/performance.md).
  const TrilinearAxis x = trilinear_axis(g, p.x, 0), y = trilinear_axis(g, p.y, 1), z = trilinear_axis(g, p.z, 2);
  out[0] = trilinear_blend<T>(g, trilinear_axis(g, p.x + 1.f, 0), y, z);
  out[1] = trilinear_blend<T>(g, trilinear_axis(g, p.x - 1.f, 0), y, z);
  out[2] = trilinear_blend<T>(g, x, trilinear_axis(g, p.y + 1.f, 1), z);
  out[3] = trilinear_blend<T>(g, x, trilinear_axis(g, p.y - 1.f, 1), z);
  out[4] = trilinear_blend<T>(g, x, y, trilinear_axis(g, p.z + 1.f, 2));
  out[5] = trilinear_blend<T>(g, x, y, trilinear_axis(g, p.z - 1.f, 2));
}

// The same for the grid's voxel type.
inline float trilinear_raw(const VoxelGrid& g, float x, float y, float z) {
  switch (g.type) {
    case VoxelType::U8: return trilinear_typed<uint8_t>(g, x, y, z);
    case VoxelType::U16: return trilinear_typed<uint16_t>(g, x, y, z);
    case VoxelType::F32: return trilinear_typed<float>(g, x, y, z);
  }
  return 0.f;
}

// The cubic B-spline from eight trilinear fetches, as common_sampling.glsl computes it.
inline float tricubic_raw(const VoxelGrid& g, float x, float y, float z) {
  const float p[3] = {x, y, z};
  float g0[3], g1[3], h0[3], h1[3];
  for (int a = 0; a < 3; ++a) {
    const float i = std::floor(p[a]), f = p[a] - i;
    const float f2 = f * f, f3 = f2 * f;
    const float w0 = (1.f - 3.f * f + 3.f * f2 - f3) / 6.f;
    const float w1 = (4.f - 6.f * f2 + 3.f * f3) / 6.f;
    const float w2 = (1.f + 3.f * f + 3.f * f2 - 3.f * f3) / 6.f;
    const float w3 = f3 / 6.f;
    g0[a] = w0 + w1;
    g1[a] = w2 + w3;
    h0[a] = i - 1.f + w1 / g0[a];  // voxel coordinates of the two fetches
    h1[a] = i + 1.f + w3 / g1[a];
  }
  const float v000 = trilinear_raw(g, h0[0], h0[1], h0[2]), v100 = trilinear_raw(g, h1[0], h0[1], h0[2]);
  const float v010 = trilinear_raw(g, h0[0], h1[1], h0[2]), v110 = trilinear_raw(g, h1[0], h1[1], h0[2]);
  const float v001 = trilinear_raw(g, h0[0], h0[1], h1[2]), v101 = trilinear_raw(g, h1[0], h0[1], h1[2]);
  const float v011 = trilinear_raw(g, h0[0], h1[1], h1[2]), v111 = trilinear_raw(g, h1[0], h1[1], h1[2]);
  const float z0 = g0[1] * (g0[0] * v000 + g1[0] * v100) + g1[1] * (g0[0] * v010 + g1[0] * v110);
  const float z1 = g0[1] * (g0[0] * v001 + g1[0] * v101) + g1[1] * (g0[0] * v011 + g1[0] * v111);
  return g0[2] * z0 + g1[2] * z1;
}

inline float sample_field(const VoxelGrid& g, const glm::vec3& x) {
  const float raw = g.tricubic ? tricubic_raw(g, x.x, x.y, x.z) : trilinear_raw(g, x.x, x.y, x.z);
  return raw * g.scale + g.bias;
}

// A run of lattice points along one ray: index j = first + k * stride for k < count, at
// t_j = t0 + j (B + A j / 2), position ((o + t d) + half) * inv_spacing (shaders/ray/ray_setup.glsl's order).
struct SampleRun {
  glm::vec3 o, d, half, inv_spacing;
  float t0 = 0, A = 0, B = 1;
  int first = 0, stride = 1, count = 0;
};
constexpr int kMaxRun = 32;  // samples per run at most

// out[k] = sample_field at the run's k-th point (SIMD where the target has it).
void sample_run(const VoxelGrid& g, const SampleRun& run, float* out);
// The SIMD target sample_run dispatches to on this machine (e.g. "AVX3", "AVX2"), and its
// float lanes (a run of fewer points costs as much as a run of that many).
const char* simd_target();
int sample_run_lanes();

}  // namespace peakcast::cpu
