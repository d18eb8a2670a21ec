// Accepts TCP connections; each gets its own strand and an HttpSession.
#pragma once

#include <memory>

#include "net/app_context.h"
#include "net/beast.h"

namespace peakcast::net {

class Listener : public std::enable_shared_from_this<Listener> {
 public:
  Listener(asio::io_context& ioc, tcp::endpoint endpoint, AppContext& app);
  void run();
  void stop();  // any thread: no more connections are accepted
  uint16_t port() const { return acceptor_.local_endpoint().port(); }

 private:
  void accept();
  asio::io_context& ioc_;
  tcp::acceptor acceptor_;
  AppContext& app_;
};

}  // namespace peakcast::net
