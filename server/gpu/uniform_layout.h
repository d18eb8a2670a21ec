// What GL reports of the ray caster's uniform block (shaders/ray/uniforms.glsl), for the test that
// holds its std140 layout to the C++ struct (render/ray_uniforms.h).
#pragma once

#include <cstddef>
#include <map>
#include <vector>
#include <string>

#include "gpu/gl_objects.h"

namespace peakcast::gpu {

// What GL reports for the linked program's RayUniforms block.
std::map<std::string, size_t> uniform_offsets(const gpu::Program& program);
size_t uniform_block_size(const gpu::Program& program);

}  // namespace peakcast::gpu
