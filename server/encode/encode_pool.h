// A fixed pool of encode threads, each with its own TurboJPEG handle (docs/architecture.md).
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "encode/jpeg.h"

namespace peakcast::encode {

class EncodePool {
 public:
  explicit EncodePool(int threads);
  ~EncodePool();  // finishes queued work, then joins
  EncodePool(const EncodePool&) = delete;
  EncodePool& operator=(const EncodePool&) = delete;

  void submit(std::function<void(JpegEncoder&)> job);
  size_t queued() const;

 private:
  void run();
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<std::function<void(JpegEncoder&)>> jobs_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace peakcast::encode
