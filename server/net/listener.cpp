#include "net/listener.h"

#include "core/log.h"

#include "net/connection_slot.h"
#include "net/http_session.h"

namespace peakcast::net {

void fail(beast::error_code ec, const char* what) {
  if (ec == asio::error::operation_aborted || ec == websocket::error::closed || ec == http::error::end_of_stream ||
      ec == asio::error::eof || ec == beast::error::timeout || ec == asio::error::connection_reset ||
      ec == asio::error::broken_pipe)
    return;
  log::warn("connection error", {{"where", what}, {"error", ec.message()}});
}

Listener::Listener(asio::io_context& ioc, tcp::endpoint endpoint, AppContext& app)
    : ioc_(ioc), acceptor_(asio::make_strand(ioc)), app_(app) {
  acceptor_.open(endpoint.protocol());
  acceptor_.set_option(asio::socket_base::reuse_address(true));
  acceptor_.bind(endpoint);  // throws system_error, e.g. address in use
  acceptor_.listen(asio::socket_base::max_listen_connections);
}

void Listener::run() { accept(); }

void Listener::stop() {
  asio::post(acceptor_.get_executor(), [self = shared_from_this()] {
    beast::error_code ec;
    self->acceptor_.close(ec);
  });
}

void Listener::accept() {
  acceptor_.async_accept(asio::make_strand(ioc_), [self = shared_from_this()](beast::error_code ec, tcp::socket s) {
    if (ec) {
      fail(ec, "accept");
      if (ec == asio::error::operation_aborted || !self->acceptor_.is_open()) return;
    } else {
      // Beyond the connection cap the socket is closed at once: a flood of idle connections
      // cannot exhaust descriptors or memory.
      beast::error_code aec;
      const auto peer = s.remote_endpoint(aec);
      if (auto slot = aec ? nullptr : self->app_.connections.take(peer.address().to_string())) {
        std::make_shared<HttpSession>(std::move(s), self->app_, std::move(slot))->run();
      } else {
        self->app_.metrics.add("peakcast_connections_refused_total", "", 1);
        beast::error_code ignored;
        s.close(ignored);
      }
    }
    self->accept();
  });
}

}  // namespace peakcast::net
