// The live WebSocket connections. The session cap is reserved here atomically at upgrade time,
// so two simultaneous upgrades can never both take the last slot; shutdown closes every
// connection listed.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <vector>

namespace peakcast::net {

class WsSession;

class SessionRegistry {
 public:
  explicit SessionRegistry(int max_sessions) : max_(max_sessions) {}
  // Takes a slot; false when all `max_sessions` are taken.
  bool try_reserve();
  void release();  // gives a reserved slot back
  int count() const { return count_.load(); }
  int max() const { return max_; }

  void track(const std::shared_ptr<WsSession>& s);
  std::vector<std::shared_ptr<WsSession>> live();

 private:
  const int max_;
  std::atomic<int> count_{0};
  std::mutex m_;
  std::vector<std::weak_ptr<WsSession>> sessions_;
};

}  // namespace peakcast::net
