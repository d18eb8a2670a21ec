// Host mirror of the std140 block in shaders/uniforms.glsl. Only vec4/ivec4 members, so the
// std140 offsets are 16 * index; a gpu test compares them with what GL reports.
#pragma once

#include <cstddef>
#include <map>
#include <vector>
#include <string>

#include <glm/vec4.hpp>

#include "gpu/gl_objects.h"

namespace peakcast::render {

struct RayUniforms {
  glm::vec4 p0;
  glm::vec4 right;
  glm::vec4 up;
  glm::vec4 forward;
  glm::vec4 box_half;
  glm::vec4 spacing;
  glm::vec4 dims;
  glm::vec4 value_map;
  glm::vec4 background;
  glm::vec4 cells;
  glm::ivec4 image;
  glm::vec4 peaks;
  glm::vec4 tables;
  // Bricks (render/brick.h), whole-volume voxel coordinates: xyz of brick_half: the offset
  // voxel_coords adds (box_half - read_lo * spacing); own_lo/own_hi: the owned box, w: the
  // axes (bits 0-2) on which it has no bound (the volume's own faces). brick_half.w: the width
  // of the front opacity's rows (ray textures; 0: none).
  glm::vec4 brick_half;
  glm::vec4 own_lo;
  glm::vec4 own_hi;
  // render.clip, box-centred (core/clip.h): lo.w 1 with a crop box, hi.w 1 with a plane; plane:
  // xyz its unit normal, w its offset.
  glm::vec4 clip_lo;
  glm::vec4 clip_hi;
  glm::vec4 clip_plane;
};

static_assert(sizeof(RayUniforms) == 19 * 16, "std140 block size");
static_assert(offsetof(RayUniforms, value_map) == 7 * 16, "std140 offset");
static_assert(offsetof(RayUniforms, image) == 10 * 16, "std140 offset");

// Member name (as in GLSL) -> byte offset, for the layout test.
std::map<std::string, size_t> host_uniform_offsets();

// What GL reports for the linked program's RayUniforms block.
std::map<std::string, size_t> gl_uniform_offsets(const gpu::Program& program);
size_t gl_uniform_block_size(const gpu::Program& program);

}  // namespace peakcast::render
