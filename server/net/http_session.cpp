#include "net/http_session.h"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <limits>

#include "net/connection_slot.h"
#include "net/rest_uploads.h"
#include "net/ws_session.h"

namespace peakcast::net {

HttpSession::HttpSession(tcp::socket&& socket, AppContext& app, std::shared_ptr<ConnectionSlot> slot)
    : stream_(std::move(socket)), app_(app), slot_(std::move(slot)), upload_deadline_(stream_.get_executor()) {}

void HttpSession::run() {
  asio::dispatch(stream_.get_executor(), [self = shared_from_this()] { self->read(); });
}

void HttpSession::read() {
  parser_.emplace();
  // No body limit while the header is read (Beast checks Content-Length against it there): an
  // upload's is its own; every other request's is set once the header names the route. (Not
  // boost::none: Boost 1.74 compares a length against an empty optional as larger.)
  parser_->body_limit(std::numeric_limits<std::uint64_t>::max());
  parser_->header_limit(uint32_t(limits::kMaxHttpHeaderBytes));
  stream_.expires_after(limits::kHandshakeTimeout);
  http::async_read_header(stream_, buffer_, *parser_,
                          [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_header(ec); });
}

// The header first: an upload's body goes to a file as it arrives (http_upload.cpp); every other
// request's body is read whole, within limits::kMaxHttpBodyBytes.
void HttpSession::on_header(beast::error_code ec) {
  if (ec) return on_read(ec);
  const auto& req = parser_->get();
  if (!host_allowed(req)) return;
  if (req.method() == http::verb::post && path_of(std::string(req.target())) == "/api/volumes") return start_upload();
  // A chunk of a chunked upload (PUT /api/uploads/{id}/chunks/...) may hold more than a request.
  const bool chunk =
      req.method() == http::verb::put && path_of(std::string(req.target())).rfind("/api/uploads/", 0) == 0;
  const uint64_t most = chunk ? uint64_t(ChunkedUploads::kMaxChunkBytes) : limits::kMaxHttpBodyBytes;
  if (auto n = parser_->content_length(); n && *n > most) return on_read(http::error::body_limit);
  parser_->body_limit(most);                                    // a chunked body is counted as it arrives
  if (chunk) stream_.expires_after(limits::kHttpWriteTimeout);  // 16 MiB from a slow link takes a while
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
  auto cancelled = std::make_shared<std::atomic<bool>>(false);
  pending_ = true;
  auto send = [self](Response res) {
    asio::post(self->stream_.get_executor(), [self, res = std::move(res)]() mutable {
      self->pending_ = false;
      self->stream_.socket().cancel();  // ends watch_for_close's wait before the write starts
      self->write(std::move(res));
    });
  };
  if (path_of(std::string(req.target())).rfind("/api/uploads", 0) == 0) {  // chunked uploads: by the client's address
    if (!origin_allowed(req)) {  // as POST /api/volumes: no other web page writes into the upload folder
      app_.metrics.add("peakcast_http_requests_total", "route=\"uploads\",code=\"403\"", 1);
      return send(error_response(req, http::status::forbidden, "forbidden_origin",
                                 "Origin " + std::string(req[http::field::origin]) + " is not allowed"));
    }
    beast::error_code ec;
    const std::string client = stream_.socket().remote_endpoint(ec).address().to_string();
    uploads_route(app_, std::move(req), client, std::move(send));
  } else {
    handle_request(app_, std::move(req), std::move(send), cancelled,
                   [self, cancelled] { return self->open_stream(cancelled); });
  }
  if (pending_) watch_for_close(cancelled);
}

// While an answer is pending (a still in the queue), notice a client that hangs up: a peek at
// the socket reads end-of-stream or an error. Data is a pipelined request: stop watching, it is
// read after the answer. Readiness can be spurious (nothing to read yet): then wait again.
void HttpSession::watch_for_close(std::shared_ptr<std::atomic<bool>> cancelled) {
  stream_.socket().async_wait(tcp::socket::wait_read, [self = shared_from_this(), cancelled](beast::error_code ec) {
    if (ec || !self->pending_) return;
    auto& sock = self->stream_.socket();
    char byte;
    beast::error_code peek, ignored;
    sock.non_blocking(true, ignored);
    const size_t n = sock.receive(asio::buffer(&byte, 1), tcp::socket::message_peek, peek);
    sock.non_blocking(false, ignored);
    if (peek == asio::error::would_block || peek == asio::error::try_again) return self->watch_for_close(cancelled);
    if (!peek && n > 0) return;
    cancelled->store(true);      // end of stream or a reset
    self->app_.render.notify();  // the scheduler drops it now, not at its turn
  });
}

// DNS rebinding: a page served from another name that resolves here must not reach the server.
// Every route is refused for a Host outside the allow-list (net/http_text.h), before any body is
// read; the connection then closes.
bool HttpSession::host_allowed(const Request& req) {
  if (app_.hosts.allowed(req[http::field::host])) return true;
  app_.metrics.add("peakcast_http_requests_total", "route=\"host\",code=\"403\"", 1);
  Request head;
  head.version(req.version());
  head.keep_alive(false);
  write(error_response(head, http::status::forbidden, "forbidden_host",
                       "Host '" + std::string(req[http::field::host]).substr(0, 200) +
                           "' is not a name this server answers to (--allowed-host)"));
  return false;
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
  const Principal who = app_.access.who(token);
  if (app_.access.required() && !token.empty() && !who.authorized) {
    app_.metrics.add("peakcast_http_requests_total", "route=\"ws\",code=\"401\"", 1);
    return write(error_response(req, http::status::unauthorized, "unauthorized", "wrong bearer token"));
  }
  // The slot is reserved now, atomically, for a client whose token is checked (or an open
  // server): simultaneous upgrades cannot exceed the cap. One that brings its token in hello
  // takes its slot then (WsSession), never before: an unauthenticated socket costs no slot. The
  // WebSocket session owns the reservation from here on and gives it back when it ends.
  if (app_.stopping.load() || (who.authorized && !app_.ws_sessions.try_reserve())) {
    app_.metrics.add("peakcast_http_requests_total", "route=\"ws\",code=\"503\"", 1);
    auto res =
        app_.stopping.load()
            ? error_response(req, http::status::service_unavailable, "shutting_down", "the server is shutting down")
            : error_response(req, http::status::service_unavailable, "session_limit",
                             "the server holds its maximum of " + std::to_string(app_.config.max_sessions) +
                                 " sessions; try again later");
    res.set(http::field::retry_after, "5");
    return write(std::move(res));
  }
  stream_.expires_never();
  std::make_shared<WsSession>(stream_.release_socket(), app_, who, std::move(slot_))->run(std::move(req));
}

void HttpSession::write(Response res) {
  const bool close = res.need_eof();
  auto sp = std::make_shared<Response>(std::move(res));
  stream_.expires_after(limits::kHttpWriteTimeout);  // the read's deadline may be long past (a queued still)
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
