#include "net/session_registry.h"

#include <algorithm>

namespace peakcast::net {

bool SessionRegistry::try_reserve() {
  int n = count_.load();
  do {
    if (n >= max_) return false;
  } while (!count_.compare_exchange_weak(n, n + 1));
  return true;
}

void SessionRegistry::release() { count_.fetch_sub(1); }

void SessionRegistry::track(const std::shared_ptr<WsSession>& s) {
  std::lock_guard lock(m_);
  sessions_.erase(std::remove_if(sessions_.begin(), sessions_.end(), [](auto& w) { return w.expired(); }),
                  sessions_.end());
  sessions_.push_back(s);
}

std::vector<std::shared_ptr<WsSession>> SessionRegistry::live() {
  std::lock_guard lock(m_);
  std::vector<std::shared_ptr<WsSession>> out;
  for (auto& w : sessions_)
    if (auto s = w.lock()) out.push_back(std::move(s));
  return out;
}

}  // namespace peakcast::net
