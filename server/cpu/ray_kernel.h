// One ray of the CPU backend: shaders/raycast_body.glsl ported to C++, the same algorithm in
// float on the same lattice (sampling.h), with the same variant switches read at run time
// (a branch the whole frame takes the same way costs a CPU next to nothing). Samples come in
// runs along the ray from sample_run (SIMD); everything after the sample is scalar.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "core/clip.h"
#include "core/ray_texture.h"
#include "cpu/sampler.h"
#include "render/variant.h"

namespace peakcast::cpu {

// A frame's inputs: the uniforms, tables and buffers the GL path binds, as host pointers.
struct CpuFrame {
  render::VariantKey key;
  VoxelGrid voxels;
  int run_lanes = 8;  // sample_run_lanes()
  // Camera (ray_setup.glsl's uniforms, box-centred).
  glm::vec3 p0{0}, right{0}, up{0}, forward{0};
  float half_w = 0, half_h = 0, dist = 0;
  glm::vec3 box_half{0};
  CenteredClip<glm::vec3, float> clip;  // render.clip, box-centred (core/clip.h)
  // Voxel coordinates of the resident voxels: (p + sample_half) * inv_spacing. box_half for a
  // whole volume; a brick's (distributed rendering) is moved by its first voxel.
  glm::vec3 sample_half{0};
  // Distributed rendering: the resident voxels are one brick of the whole volume, whose box,
  // camera and lattice the frame keeps. A ray takes only the lattice points inside the brick's
  // own box [own_lo, own_hi) in the whole volume's voxel coordinates
  // plus, for segment methods, the point after them that closes the last
  // segment (a segment belongs to the rank owning its first point). No bound where the box
  // meets the volume's own faces (at_start, at_end).
  bool brick = false;
  glm::vec3 own_lo{0}, own_hi{0};
  bool at_start[3] = {false, false, false}, at_end[3] = {false, false, false};
  // Ray textures on a brick: the opacity in front of it per pixel of the drawn rect (rect_x,
  // rect_y: its first pixel; rect_w its width); null for the front brick (render/brick.h).
  const float* front_opacity = nullptr;
  int rect_x = 0, rect_y = 0, rect_w = 0;
  float step = 1;  // the uniform step
  glm::vec3 spacing{1}, inv_spacing{1};
  float stop = 1;  // early-termination opacity
  int sample_cap = 0;
  int image_w = 1, image_h = 1;
  // Macrocells: one byte per cell in grid order.
  int grid[3] = {1, 1, 1};
  float cell_edge = 8;
  const uint8_t* cell_distance = nullptr;  // space skipping
  // Space skipping found no occupied cell: no ray samples anything, every pixel is background.
  bool nothing_visible = false;
  const uint8_t* cell_stride = nullptr;    // adaptive multipliers
  // Per-TF tables.
  const float* tf = nullptr;  // TransferFunction::kTableSize RGBA, opacity for `step`
  int tf_size = 0;
  const uint64_t* tf_alpha_any = nullptr;  // bit i: texel i or i + 1 has opacity (tf_cell_bits)
  const float* peak_texels = nullptr;  // [layer][j][i][4], TF coordinates, kNoPeakTexel = none
  // Bit j * peak_bins + i: texel (i, j) of layer 0 holds a peak (peak_texel_bits). A segment
  // whose bit is clear finds none without reading the table, which misses the cache.
  const uint64_t* peak_any = nullptr;
  int peak_bins = 0, peak_layers = 0, max_peaks = 0, secant_iterations = 0;
  const glm::vec4* tf_points = nullptr;  // tf_point_pairs
  int tf_point_count = 0;
  const float* preint = nullptr;  // [j][i][4]
  int preint_size = 0;
  // Bit j * (preint_size - 1) + i: one of the texels (i..i+1, j..j+1) that a lookup in that cell
  // interpolates is not all zero (preint_cell_bits). A clear bit: the segment adds nothing.
  const uint64_t* preint_any = nullptr;
  const RayTexture* ray_texture = nullptr;
  float diff_k = 0, min_step = 0;  // differential sampling
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
// Benchmark baseline: the same ray's first `budget` lattice points, reconstruction only.
RayResult cast_ray_bare(const CpuFrame& f, float px, float py, int budget);

}  // namespace peakcast::cpu
