// The GL renderer's helpers that gl_renderer.cpp and gl_renderer_tables.cpp share. Internal to
// server/gpu.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/macrocells.h"
#include "core/transfer_function.h"
#include "gpu/gl_objects.h"
#include "render/small_cache.h"

namespace peakcast::gpu {

// One byte per macrocell (empty-space distance, adaptive multiplier) in grid order, packed four
// to a uint (little end first) into a shader storage buffer (cell_byte in sampling.glsl).
Buffer make_cell_buffer(const MacrocellGrid& cells, const std::vector<uint8_t>& bytes);

}  // namespace peakcast::gpu
