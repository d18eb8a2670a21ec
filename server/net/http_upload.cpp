// POST /api/volumes: a volume upload, streamed from the socket into the upload store's file
// (session/upload_store.h) as it arrives, with no more than a read buffer in memory. Refused
// before a byte of the body is read when the token, the Origin, the rate, the uploads at once
// or the announced size say no; a client that sends Expect: 100-continue hears the refusal
// before sending the body. An upload that stalls (no bytes for --upload-timeout) or a client
// that goes away ends it, and its file is removed. Checked and registered on the loader pool.
#include <boost/asio/post.hpp>

#include "core/utf8.h"
#include "net/http_session.h"

namespace peakcast::net {

void HttpSession::refuse_upload(int status, const std::string& code, const std::string& message, int retry_after_s) {
  app_.metrics.add("peakcast_uploads_total", "outcome=\"" + code + "\"", 1);
  app_.metrics.add("peakcast_http_requests_total", "route=\"upload\",code=\"" + std::to_string(status) + "\"", 1);
  Request req;
  req.version(parser_ ? parser_->get().version() : 11);
  req.keep_alive(false);  // the body (or the rest of it) is not read: the connection ends
  upload_.reset();        // its file goes now
  upload_parser_.reset();
  upload_deadline_.cancel();
  auto res = error_response(req, http::status(status), code, message);
  if (retry_after_s > 0 || status == 503 || status == 429)
    res.set(http::field::retry_after, std::to_string(retry_after_s > 0 ? retry_after_s : 5));
  write(std::move(res));
}

void HttpSession::start_upload() {
  const auto& req = parser_->get();
  const std::string target(req.target());
  const Principal who = app_.access.who(token_from(std::string(req[http::field::authorization]), target));
  if (!who.authorized) return refuse_upload(401, "unauthorized", "missing or wrong bearer token");
  if (!origin_allowed(req))
    return refuse_upload(403, "forbidden_origin",
                         "Origin " + std::string(req[http::field::origin]) + " is not allowed");
  std::optional<int64_t> length;
  if (auto n = parser_->content_length()) length = int64_t(*n);
  if (parser_->is_done() || length == 0) return refuse_upload(400, "bad_upload", "the upload has no body");
  beast::error_code ec;
  std::string client = stream_.socket().remote_endpoint(ec).address().to_string();
  try {
    upload_ = app_.uploads.begin(client, length);
  } catch (const UploadRefusal& r) {
    return refuse_upload(r.status, r.code, r.what(), r.retry_after_s);
  }
  upload_params_ = UploadParams{};
  upload_start_ = {};
  upload_received_ = 0;
  upload_params_.name = url_decode(query_param(target, "name"));
  upload_params_.owner = who.name;
  upload_params_.content_type = std::string(req[http::field::content_type]);
  // Raw voxels: their header as query parameters (dims=X,Y,Z&dtype=uint16&spacing=..&origin=..).
  upload_params_.raw = raw_header_from_query(target);
  if (upload_params_.raw && length && upload_params_.content_type.rfind("multipart/form-data", 0) != 0) try {
      app_.uploads.check_raw_header(*upload_params_.raw, *length);
    } catch (const UploadRefusal& r) {
      return refuse_upload(r.status, r.code, r.what(), r.retry_after_s);
    }
  const bool expects_continue = beast::iequals(req[http::field::expect], "100-continue");
  upload_parser_.emplace(std::move(*parser_));
  parser_.reset();
  upload_parser_->body_limit(uint64_t(app_.uploads.limits().max_bytes));
  upload_parser_->get().body().open(upload_->file().c_str(), beast::file_mode::write, ec);
  if (ec) return refuse_upload(507, "upload_failed", "the upload could not be stored on the server");
  if (!expects_continue) return read_upload();
  auto cont =
      std::make_shared<http::response<http::empty_body>>(http::status::continue_, upload_parser_->get().version());
  stream_.expires_after(limits::kHttpWriteTimeout);
  http::async_write(stream_, *cont, [self = shared_from_this(), cont](beast::error_code ec, std::size_t) {
    if (ec) return fail(ec, "upload continue");
    self->read_upload();
  });
}

// Each read waits at most the idle timeout, and never past the whole body's deadline. After the
// first idle timeout the average rate must stay above the minimum: a trickle (a byte every few
// seconds) is ended instead of holding an upload slot for as long as it lasts.
void HttpSession::read_upload() {
  const auto& l = app_.uploads.limits();
  if (upload_start_ == std::chrono::steady_clock::time_point{}) {
    upload_start_ = std::chrono::steady_clock::now();
    deadline_passed_ = false;
    upload_deadline_.expires_after(l.deadline);
    upload_deadline_.async_wait([weak = weak_from_this()](beast::error_code ec) {
      auto self = weak.lock();
      if (ec || !self || !self->upload_parser_) return;  // cancelled: the body is whole, or refused
      self->deadline_passed_ = true;
      beast::error_code ignored;
      self->stream_.socket().cancel(ignored);  // the read ends with operation_aborted
    });
  }
  stream_.expires_after(l.idle_timeout);
  http::async_read_some(
      stream_, buffer_, *upload_parser_,
      [self = shared_from_this()](beast::error_code ec, std::size_t n) { self->on_upload_read(ec, n); });
}

void HttpSession::on_upload_read(beast::error_code ec, std::size_t bytes) {
  upload_received_ += bytes;
  const auto& l = app_.uploads.limits();
  if (deadline_passed_)
    return refuse_upload(
        408, "upload_too_slow",
        "an upload must arrive whole within " + std::to_string(l.deadline.count()) + " s (--upload-deadline)");
  if (!ec && !upload_parser_->is_done()) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - upload_start_).count();
    if (seconds > double(l.idle_timeout.count()) && double(upload_received_) < l.min_bytes_per_second * seconds)
      return refuse_upload(408, "upload_too_slow",
                           "the upload arrives at " + std::to_string(int64_t(double(upload_received_) / seconds)) +
                               " bytes/s, below the minimum of " + std::to_string(int64_t(l.min_bytes_per_second)) +
                               " (--upload-min-rate-kib)");
  }
  if (ec == http::error::body_limit)
    return refuse_upload(
        413, "too_large",
        "an upload may hold " + std::to_string(app_.uploads.limits().max_bytes >> 20) + " MiB (--max-upload-mib)");
  if (ec) {  // gone, reset, or stalled past --upload-timeout: the file goes with the ticket
    app_.metrics.add("peakcast_uploads_total",
                     ec == beast::error::timeout ? "outcome=\"timeout\"" : "outcome=\"disconnected\"", 1);
    upload_.reset();
    upload_parser_.reset();
    upload_deadline_.cancel();
    return fail(ec, "upload read");
  }
  if (!upload_parser_->is_done()) return read_upload();
  upload_deadline_.cancel();
  upload_parser_->get().body().close();
  const unsigned version = upload_parser_->get().version();
  const bool keep_alive = upload_parser_->get().keep_alive();
  upload_parser_.reset();
  stream_.expires_never();  // checking a large volume takes seconds on the loader pool
  pending_ = true;
  // Checked and registered on the loader pool (reading a volume takes seconds), answered here.
  asio::post(app_.loader, [self = shared_from_this(), ticket = std::move(upload_), params = upload_params_, version,
                           keep_alive]() mutable {
    Request req;
    req.version(version);
    req.keep_alive(keep_alive);
    Response res;
    std::string outcome = "ok";
    try {
      auto entry = self->app_.uploads.commit(std::move(ticket), params);
      res = json_response(req, http::status::created, json_text(entry->info(false)));
      res.set(http::field::location, "/api/volumes/" + entry->id);
    } catch (const UploadRefusal& r) {
      outcome = r.code;
      res = error_response(req, http::status(r.status), r.code, r.what());
    } catch (const std::exception& e) {  // nothing escapes a loader-pool handler
      outcome = "upload_failed";
      res = error_response(req, http::status::internal_server_error, "upload_failed", e.what());
    }
    self->app_.metrics.add("peakcast_uploads_total", "outcome=\"" + outcome + "\"", 1);
    self->app_.metrics.add("peakcast_http_requests_total",
                           "route=\"upload\",code=\"" + std::to_string(res.result_int()) + "\"", 1);
    asio::post(self->stream_.get_executor(), [self, res = std::move(res)]() mutable {
      self->pending_ = false;
      self->write(std::move(res));
    });
  });
}

}  // namespace peakcast::net
