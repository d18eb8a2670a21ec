// A compute program run over a table: one invocation per row, the rows from a storage buffer in,
// the results to one out. For tests that hold GLSL functions to their C++ build case by case
// (tests/gpu/ray_functions_test.cpp).
#pragma once

#include <cstddef>
#include <vector>

#include "gpu/gl_objects.h"

namespace peakcast::gpu {

struct ComputeTable {
  const void* uniforms = nullptr;  // bound as a uniform block at ubo_binding (null: none)
  size_t uniform_bytes = 0;
  unsigned ubo_binding = 0;
  std::vector<float> in;  // the rows, at storage binding in_binding
  unsigned in_binding = 0;
  size_t out_floats = 0;  // the results' size, at storage binding out_binding (zeroed first)
  unsigned out_binding = 1;
  int rows = 0;  // invocations: the program's local size is 64 and it skips rows >= this
};

// Runs `program` over the table and returns its results.
std::vector<float> run_compute_table(const Program& program, const ComputeTable& table);

}  // namespace peakcast::gpu
