#include "net/http_session.h"

#include <algorithm>

#include "net/ws_session.h"

namespace peakcast::net {

HttpSession::HttpSession(tcp::socket&& socket, AppContext& app) : stream_(std::move(socket)), app_(app) {}

void HttpSession::run() {
  asio::dispatch(stream_.get_executor(), [self = shared_from_this()] { self->read(); });
}

void HttpSession::read() {
  parser_.emplace();
  parser_->body_limit(limits::kMaxHttpBodyBytes);
  parser_->header_limit(uint32_t(limits::kMaxHttpHeaderBytes));
  stream_.expires_after(limits::kHandshakeTimeout);
  http::async_read(stream_, buffer_, *parser_,
                   [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
}

void HttpSession::on_read(beast::error_code ec) {
  if (ec == http::error::end_of_stream) {
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    return;
  }
  if (ec == http::error::body_limit || ec == http::error::header_limit) {
    Request req;
    req.version(11);
    req.keep_alive(false);
    return write(error_response(req, http::status::payload_too_large, "too_large",
                                "request exceeds " + std::to_string(limits::kMaxHttpBodyBytes) + " bytes"));
  }
  if (ec) return fail(ec, "http read");
  Request req = parser_->release();
  if (websocket::is_upgrade(req)) return upgrade(std::move(req));
  auto self = shared_from_this();
  handle_request(app_, std::move(req), [self](Response res) {
    asio::post(self->stream_.get_executor(), [self, res = std::move(res)]() mutable { self->write(std::move(res)); });
  });
}

bool HttpSession::origin_allowed(const Request& req) const {
  const std::string origin(req[http::field::origin]);
  if (origin.empty()) return true;  // not a browser: scripts and tools
  const std::string host(req[http::field::host]);
  if (origin == "http://" + host || origin == "https://" + host) return true;  // the page this server served
  const auto& list = app_.config.allow_origins;
  return std::find(list.begin(), list.end(), origin) != list.end() ||
         std::find(list.begin(), list.end(), "*") != list.end();
}

void HttpSession::upgrade(Request req) {
  if (path_of(std::string(req.target())) != "/ws")
    return write(error_response(req, http::status::not_found, "not_found", "WebSocket endpoint is /ws"));
  if (!origin_allowed(req)) {
    app_.metrics.add("peakcast_http_requests_total", "route=\"ws\",code=\"403\"", 1);
    return write(error_response(req, http::status::forbidden, "forbidden_origin",
                                "Origin " + std::string(req[http::field::origin]) + " is not allowed"));
  }
  const std::string token = token_from(std::string(req[http::field::authorization]), std::string(req.target()));
  if (!app_.config.token.empty() && !token.empty() && token != app_.config.token) {
    app_.metrics.add("peakcast_http_requests_total", "route=\"ws\",code=\"401\"", 1);
    return write(error_response(req, http::status::unauthorized, "unauthorized", "wrong bearer token"));
  }
  if (app_.ws_sessions.load() >= app_.config.max_sessions) {
    app_.metrics.add("peakcast_http_requests_total", "route=\"ws\",code=\"503\"", 1);
    auto res = error_response(req, http::status::service_unavailable, "session_limit",
                              "the server holds its maximum of " + std::to_string(app_.config.max_sessions) +
                                  " sessions; try again later");
    res.set(http::field::retry_after, "5");
    return write(std::move(res));
  }
  const bool authorized = app_.config.token.empty() || token == app_.config.token;
  stream_.expires_never();
  std::make_shared<WsSession>(stream_.release_socket(), app_, authorized)->run(std::move(req));
}

void HttpSession::write(Response res) {
  const bool close = res.need_eof();
  auto sp = std::make_shared<Response>(std::move(res));
  http::async_write(stream_, *sp, [self = shared_from_this(), sp, close](beast::error_code ec, std::size_t) {
    if (ec) return fail(ec, "http write");
    if (close) {
      self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    self->read();
  });
}

}  // namespace peakcast::net
