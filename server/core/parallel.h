// Small helpers to split loops over the machine's cores.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <thread>
#include <vector>

namespace peakcast {

inline int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

// Calls fn(begin, end, worker) on contiguous chunks of [0, n) from hardware_threads() threads.
inline void parallel_chunks(size_t n, const std::function<void(size_t, size_t, int)>& fn) {
  const int workers = int(std::min<size_t>(size_t(hardware_threads()), std::max<size_t>(n, 1)));
  if (workers <= 1) {
    fn(0, n, 0);
    return;
  }
  std::vector<std::thread> threads;
  const size_t chunk = (n + workers - 1) / workers;
  for (int w = 0; w < workers; ++w) {
    size_t b = std::min(n, w * chunk), e = std::min(n, b + chunk);
    threads.emplace_back([&fn, b, e, w] { fn(b, e, w); });
  }
  for (auto& t : threads) t.join();
}

// Calls fn(item) for item in [0, n) with dynamic scheduling (items of uneven cost).
void parallel_for(size_t n, const std::function<void(size_t)>& fn, int threads = 0);

}  // namespace peakcast
