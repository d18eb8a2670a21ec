#include "core/parallel.h"

#include <atomic>
#include <exception>
#include <mutex>

namespace peakcast {

void parallel_for(size_t n, const std::function<void(size_t)>& fn, int threads) {
  if (threads <= 0) threads = hardware_threads();
  threads = int(std::min<size_t>(size_t(threads), std::max<size_t>(n, 1)));
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&] {
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      try {
        fn(i);
      } catch (...) {
        std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace peakcast
