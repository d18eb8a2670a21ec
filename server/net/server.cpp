#include "net/server.h"

#include <csignal>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "core/log.h"
#include "net/listener.h"
#include "net/ws_session.h"

namespace peakcast::net {

Server::Server(ServerConfig config)
    : app_(std::make_unique<AppContext>(std::move(config))), ioc_(app_->config.io_threads) {
  for (const auto& v : app_->config.volumes) {
    auto e = app_->volumes.preload(v);
    log::info(
        "volume loaded",
        {{"path", v.string()}, {"id", e->id}, {"volume", e->volume->to_string()}, {"load_ms", e->volume->load_ms}});
  }
}

Server::~Server() { stop(); }

void Server::start() {
  app_->render.start();
  auto address = asio::ip::make_address(app_->config.bind);
  listener_ = std::make_shared<Listener>(ioc_, tcp::endpoint{address, app_->config.port}, *app_);
  port_ = listener_->port();
  listener_->run();
  for (int i = 0; i < std::max(1, app_->config.io_threads); ++i) threads_.emplace_back([this] { ioc_.run(); });
}

void Server::run_until_signal() {
  asio::io_context signals_ctx;
  asio::signal_set signals(signals_ctx, SIGINT, SIGTERM);
  signals.async_wait([](beast::error_code, int) {});
  signals_ctx.run();
  // Containers send SIGKILL after a grace period: if the graceful path below has not finished by
  // kShutdownGrace, leave anyway.
  std::thread([] {
    std::this_thread::sleep_for(limits::kShutdownGrace);
    log::error("shutdown took too long: exiting now", {{"grace_ms", limits::kShutdownGrace.count()}});
    std::_Exit(1);
  }).detach();
  stop();
}

// Graceful: stop accepting, refuse new and queued work, end the current render at band
// granularity, send every WebSocket a close frame, give answers and close frames a moment to go
// out, then stop the io threads.
void Server::stop() {
  if (stopped_) return;
  stopped_ = true;
  const auto t0 = std::chrono::steady_clock::now();
  log::info("shutting down", {{"sessions", app_->ws_sessions.count()}, {"stills", app_->render.stills_pending()}});
  app_->stopping = true;
  if (listener_) listener_->stop();
  for (auto& ws : app_->ws_sessions.live()) ws->shut_down();
  app_->render.stop();
  while (app_->ws_sessions.count() > 0 && std::chrono::steady_clock::now() - t0 < limits::kCloseFlush)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ioc_.stop();
  for (auto& t : threads_) t.join();
  threads_.clear();
  // Volume loads and probes still running hold their connections; they finish now and post their
  // answers into the stopped io_context, which frees them while it still exists (it is
  // destroyed before app_: a job ending after it would close a socket on freed memory).
  app_->loader.join();
  app_->pyramid.join();  // a reduction of the finest level stops at its next brick (app_->stopping)
}

}  // namespace peakcast::net
