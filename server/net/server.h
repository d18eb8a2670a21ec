// The server: io threads running the listener and connections, the render service, the volumes.
#pragma once

#include <memory>
#include <thread>
#include <vector>

#include "net/app_context.h"
#include "net/beast.h"

namespace peakcast::net {

class Server {
 public:
  explicit Server(ServerConfig config);  // loads the preloaded volumes; throws on bad ones
  ~Server();
  // Binds, starts the render thread and the io threads. Throws (address in use, no GL).
  void start();
  uint16_t port() const { return port_; }
  void run_until_signal();  // SIGINT / SIGTERM, then stop(); exits the process if that takes past kShutdownGrace
  void stop();              // graceful; idempotent
  AppContext& app() { return *app_; }

 private:
  std::unique_ptr<AppContext> app_;
  asio::io_context ioc_;
  std::shared_ptr<class Listener> listener_;  // after ioc_: destroyed before the context it uses
  std::vector<std::thread> threads_;
  uint16_t port_ = 0;
  bool stopped_ = false;
};

}  // namespace peakcast::net
