// Small most-recent-first caches for a renderer's per-frame inputs (TF tables, peak and
// preintegration tables, occupancy, adaptive multipliers), keyed by what they depend on, and
// the timing helper both backends use.
#pragma once

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

namespace peakcast::render {

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

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
