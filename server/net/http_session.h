// One HTTP connection: REST, static files, and the upgrade to a WebSocket at /ws (with the
// Origin allow-list, the bearer token and the session cap checked first).
#pragma once

#include <atomic>
#include <chrono>
#include <deque>
#include <memory>
#include <optional>

#include "net/app_context.h"
#include "net/beast.h"
#include "net/response_stream.h"
#include "net/rest_routes.h"

namespace peakcast::net {

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, AppContext& app, std::shared_ptr<class ConnectionSlot> slot);
  void run();

 private:
  void read();
  void on_header(beast::error_code ec);
  void on_read(beast::error_code ec);
  // POST /api/volumes (http_upload.cpp): the body streamed into the upload store's file.
  void start_upload();
  void read_upload();
  void on_upload_read(beast::error_code ec, std::size_t bytes);
  void refuse_upload(int status, const std::string& code, const std::string& message, int retry_after_s = 0);
  void upgrade(Request req);
  void write(Response res);
  bool origin_allowed(const Request& req) const;
  bool host_allowed(const Request& req);  // false: refused (403 forbidden_host), answered here
  void watch_for_close(std::shared_ptr<std::atomic<bool>> cancelled);
  // A response written as it is made (http_stream.cpp): the request's ResponseStream.
  class Stream;
  std::shared_ptr<ResponseStream> open_stream(std::shared_ptr<std::atomic<bool>> cancelled);
  void stream_begin(StreamHeader header);
  void stream_pump();
  void stream_failed(beast::error_code ec);

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  AppContext& app_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::optional<http::request_parser<http::file_body>> upload_parser_;
  std::unique_ptr<UploadStore::Ticket> upload_;
  UploadParams upload_params_;
  std::chrono::steady_clock::time_point upload_start_;  // the body's first read: rate and deadline
  uint64_t upload_received_ = 0;
  // The whole body's deadline (--upload-deadline): cancels the read, so the 408 can still be sent
  // (a stream timeout would close the socket first).
  asio::steady_timer upload_deadline_;
  bool deadline_passed_ = false;
  std::shared_ptr<ConnectionSlot> slot_;
  bool pending_ = false;  // a request is being answered (on the strand)
  // The streamed response (on the strand): its header and serializer, what waits to be written
  // (`last`: the end; `abort`: close without it), whether a write is under way.
  struct StreamItem {
    std::string bytes;
    bool last = false, abort = false;
  };
  std::optional<StreamHeader> stream_head_;
  std::optional<http::response_serializer<http::empty_body>> stream_serializer_;
  std::deque<StreamItem> stream_queue_;
  std::vector<std::function<void()>> stream_drained_;
  std::shared_ptr<std::atomic<size_t>> stream_queued_;
  std::shared_ptr<std::atomic<bool>> stream_cancelled_;
  bool stream_writing_ = false, stream_chunked_ = true, stream_dead_ = false;
};

}  // namespace peakcast::net
