// One ray of the CPU backend: the same algorithm as the GL shader, in float on the same lattice,
// with the same variant switches read at run time (a branch the whole frame takes the same way
// costs a CPU next to nothing). What both write once (shaders/ray/) is compiled into the CPU's
// RayCaster; samples come in runs along the ray from sample_run (SIMD).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "core/ray_texture.h"
#include "cpu/sampler.h"
#include "render/ray_uniforms.h"
#include "render/variant.h"

namespace peakcast::cpu {

// A frame's inputs: the uniforms, tables and buffers the GL path binds, as host pointers.
struct CpuFrame {
  render::VariantKey key;
  VoxelGrid voxels;
  int run_lanes = 8;       // sample_run_lanes()
  bool dense_runs = true;  // plain DVR's fast path over runs of points (the walks' dense_run hook)
  // The uniforms and switches the shared ray code reads (shaders/ray/uniforms.glsl, variant.glsl),
  // filled by render/ray_uniforms.cpp as for GL. The CPU's sampler reads the voxels in TF
  // coordinates itself (VoxelGrid): value_scale and value_bias are GL's.
  ray::RayUniforms u{};
  ray::Variant v{};
  // Distributed rendering (v.brick): the resident voxels are one brick of the whole volume, whose
  // box, camera and lattice the frame keeps (u: own_lo, own_hi, open_lo, open_hi, sample_half).
  // Ray textures on a brick: the opacity in front of it per pixel of the drawn rect (rows of
  // u.front_opacity_width from (u.tile_x, u.tile_y)); null for the front brick (render/brick.h).
  const float* front_opacity = nullptr;
  // Macrocells: one byte per cell in grid order.
  const uint8_t* cell_distance = nullptr;  // space skipping
  // Space skipping found no occupied cell: no ray samples anything, every pixel is background.
  bool nothing_visible = false;
  const uint8_t* cell_stride = nullptr;   // adaptive multipliers
  const glm::vec2* cell_range = nullptr;  // maximum and minimum projections: (min, max), TF coordinates
  // Per-TF tables.
  const float* tf = nullptr;               // TransferFunction::kTableSize RGBA, opacity for `step`
  const uint64_t* tf_alpha_any = nullptr;  // bit i: texel i or i + 1 has opacity (tf_cell_bits)
  const float* peak_texels = nullptr;      // [layer][j][i][4], TF coordinates, kNoPeakTexel = none
  // Bit j * peak_bins + i: texel (i, j) of layer 0 holds a peak (peak_texel_bits). A segment
  // whose bit is clear finds none without reading the table, which misses the cache.
  const uint64_t* peak_any = nullptr;
  const glm::vec4* tf_points = nullptr;  // tf_point_pairs
  const float* preint = nullptr;         // [j][i][4]
  // Bit j * (preint_size - 1) + i: one of the texels (i..i+1, j..j+1) that a lookup in that cell
  // interpolates is not all zero (preint_cell_bits). A clear bit: the segment adds nothing.
  const uint64_t* preint_any = nullptr;
  const RayTexture* ray_texture = nullptr;
};

struct RayResult {
  glm::vec4 acc{0.f};   // premultiplied colour and opacity, not yet over the background
  float samples = 0.f;  // filter evaluations (root-solving steps included); -1: missed the box
};

// The ray through pixel centre (px, py) of the full image (row 0 at the top).
RayResult cast_ray(const CpuFrame& f, float px, float py);
// n rays at once, the same results as cast_ray each: with space skipping by leaps, the leaps up
// to each ray's first occupied cell are taken for a packet of rays in SIMD lanes.
constexpr int kRayPacket = 16;
void cast_rays(const CpuFrame& f, const float* px, const float* py, int n, RayResult* out);

}  // namespace peakcast::cpu
