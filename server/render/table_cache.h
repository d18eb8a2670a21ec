// The ray caster's per-frame inputs kept in small most-recent-first caches (TF tables, peak
// and preintegration tables, occupancy, adaptive multipliers, ray textures): the helpers
// raycaster.cpp and raycaster_tables.cpp share. Internal to server/render.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "core/macrocells.h"
#include "core/transfer_function.h"
#include "gpu/gl_objects.h"

namespace peakcast::render {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string tf_signature(const TransferFunction& tf, double lo, double hi);
// One byte per macrocell (empty-space distance, adaptive multiplier) in grid order, packed four
// to a uint (little end first) into a shader storage buffer (cell_byte in sampling.glsl).
gpu::Buffer make_cell_buffer(const MacrocellGrid& cells, const std::vector<uint8_t>& bytes);

// Moves the entry named `key` to the front of a most-recent-first cache; nullptr when absent.
template <class T>
T* cache_find(std::vector<T>& cache, const std::string& key) {
  auto it = std::find_if(cache.begin(), cache.end(), [&](const T& e) { return e.key == key; });
  if (it == cache.end()) return nullptr;
  std::rotate(cache.begin(), it, it + 1);
  return &cache.front();
}

// Puts `e` at the front, dropping the least recently used entry beyond `cap`.
template <class T>
T& cache_insert(std::vector<T>& cache, T e, size_t cap) {
  if (cache.size() >= cap) cache.pop_back();
  cache.insert(cache.begin(), std::move(e));
  return cache.front();
}

}  // namespace peakcast::render
