#include "encode/encode_pool.h"

#include <cstdio>
#include <exception>

namespace peakcast::encode {

EncodePool::EncodePool(int threads) {
  for (int t = 0; t < std::max(1, threads); ++t) threads_.emplace_back([this] { run(); });
}

EncodePool::~EncodePool() {
  {
    std::lock_guard lock(m_);
    stopping_ = true;
  }
  cv_.notify_all();
  for (auto& t : threads_) t.join();
}

void EncodePool::submit(std::function<void(JpegEncoder&)> job) {
  {
    std::lock_guard lock(m_);
    jobs_.push_back(std::move(job));
  }
  cv_.notify_one();
}

size_t EncodePool::queued() const {
  std::lock_guard lock(m_);
  return jobs_.size();
}

void EncodePool::run() {
  JpegEncoder encoder;
  for (;;) {
    std::function<void(JpegEncoder&)> job;
    {
      std::unique_lock lock(m_);
      cv_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
      if (jobs_.empty()) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    try {
      job(encoder);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "peakcast: encode job failed: %s\n", e.what());
    }
  }
}

}  // namespace peakcast::encode
