// One open TCP connection counted against the connection caps (limits::kMaxConnections in all,
// limits::kMaxConnectionsPerAddress per client address), from accept until the connection ends:
// it moves from the HTTP session to the WebSocket session on upgrade.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace peakcast::net {

class ConnectionCounter {
 public:
  ConnectionCounter(int max_total, int max_per_address) : max_total_(max_total), max_per_address_(max_per_address) {}
  // A slot for a connection from `address`; nullptr when a cap is reached.
  std::shared_ptr<class ConnectionSlot> take(const std::string& address);
  int open() const;

 private:
  friend class ConnectionSlot;
  void give_back(const std::string& address);
  const int max_total_, max_per_address_;
  mutable std::mutex m_;
  int total_ = 0;
  std::map<std::string, int> per_address_;
};

class ConnectionSlot {
 public:
  ConnectionSlot(ConnectionCounter& counter, std::string address) : counter_(counter), address_(std::move(address)) {}
  ~ConnectionSlot() { counter_.give_back(address_); }
  ConnectionSlot(const ConnectionSlot&) = delete;
  ConnectionSlot& operator=(const ConnectionSlot&) = delete;

 private:
  ConnectionCounter& counter_;
  std::string address_;
};

inline std::shared_ptr<ConnectionSlot> ConnectionCounter::take(const std::string& address) {
  {
    std::lock_guard lock(m_);
    int& mine = per_address_[address];
    if (total_ >= max_total_ || mine >= max_per_address_) {
      if (mine == 0) per_address_.erase(address);
      return nullptr;
    }
    ++total_;
    ++mine;
  }
  return std::make_shared<ConnectionSlot>(*this, address);
}

inline void ConnectionCounter::give_back(const std::string& address) {
  std::lock_guard lock(m_);
  --total_;
  if (--per_address_[address] <= 0) per_address_.erase(address);
}

inline int ConnectionCounter::open() const {
  std::lock_guard lock(m_);
  return total_;
}

}  // namespace peakcast::net
