#include "net/server.h"

#include <csignal>
#include <cstdio>

#include "net/listener.h"

namespace peakcast::net {

Server::Server(ServerConfig config) : app_(std::make_unique<AppContext>(std::move(config))), ioc_(app_->config.io_threads) {
  for (const auto& v : app_->config.volumes) {
    auto e = app_->volumes.preload(v);
    std::printf("peakcast: loaded %s as '%s' (%s) in %.0f ms\n", v.c_str(), e->id.c_str(),
                e->volume->to_string().c_str(), e->volume->load_ms);
  }
}

Server::~Server() { stop(); }

void Server::start() {
  app_->render.start();
  auto address = asio::ip::make_address(app_->config.bind);
  auto listener = std::make_shared<Listener>(ioc_, tcp::endpoint{address, app_->config.port}, *app_);
  port_ = listener->port();
  listener->run();
  for (int i = 0; i < std::max(1, app_->config.io_threads); ++i) threads_.emplace_back([this] { ioc_.run(); });
}

void Server::run_until_signal() {
  asio::io_context signals_ctx;
  asio::signal_set signals(signals_ctx, SIGINT, SIGTERM);
  signals.async_wait([](beast::error_code, int) {});
  signals_ctx.run();
  stop();
}

void Server::stop() {
  if (stopped_) return;
  stopped_ = true;
  ioc_.stop();
  for (auto& t : threads_) t.join();
  threads_.clear();
  app_->render.stop();
}

}  // namespace peakcast::net
