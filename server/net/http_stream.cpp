// A response written as it is made (net/response_stream.h): the header through Beast's
// serializer, then each piece as one chunk of the chunked transfer encoding (HTTP/1.1) or as raw
// bytes up to the connection's close (HTTP/1.0), then the last chunk. Everything runs on the
// connection's strand; the producer's threads only post.
#include "net/http_session.h"

namespace peakcast::net {

class HttpSession::Stream final : public ResponseStream {
 public:
  Stream(std::shared_ptr<HttpSession> s, std::shared_ptr<std::atomic<size_t>> queued)
      : s_(std::move(s)), queued_(std::move(queued)) {}

  void begin(StreamHeader header) override {
    asio::post(s_->stream_.get_executor(),
               [s = s_, h = std::move(header)]() mutable { s->stream_begin(std::move(h)); });
  }
  void write(std::string bytes) override {
    if (bytes.empty()) return;  // an empty chunk would end the body
    queued_->fetch_add(bytes.size());
    push({std::move(bytes), false, false});
  }
  void end() override { push({std::string(), true, false}); }
  void abort() override { push({std::string(), false, true}); }
  size_t queued_bytes() const override { return queued_->load(); }
  void when_drained(std::function<void()> f) override {
    asio::post(s_->stream_.get_executor(), [s = s_, f = std::move(f)]() mutable {
      if (s->stream_dead_ || (!s->stream_writing_ && s->stream_queue_.empty())) return f();
      s->stream_drained_.push_back(std::move(f));
    });
  }

 private:
  void push(StreamItem item) {
    asio::post(s_->stream_.get_executor(), [s = s_, item = std::move(item)]() mutable {
      s->stream_queue_.push_back(std::move(item));
      s->stream_pump();
    });
  }
  std::shared_ptr<HttpSession> s_;
  std::shared_ptr<std::atomic<size_t>> queued_;
};

std::shared_ptr<ResponseStream> HttpSession::open_stream(std::shared_ptr<std::atomic<bool>> cancelled) {
  stream_queued_ = std::make_shared<std::atomic<size_t>>(0);
  stream_cancelled_ = std::move(cancelled);
  return std::make_shared<Stream>(shared_from_this(), stream_queued_);
}

void HttpSession::stream_begin(StreamHeader header) {
  pending_ = false;
  stream_.socket().cancel();  // ends watch_for_close's wait: a failed write tells from here on
  stream_chunked_ = header.version() >= 11;
  if (stream_chunked_) {
    header.chunked(true);
  } else {
    header.keep_alive(false);  // HTTP/1.0: the body ends with the connection
  }
  stream_head_.emplace(std::move(header));
  stream_serializer_.emplace(*stream_head_);
  stream_writing_ = true;
  stream_.expires_after(limits::kHttpWriteTimeout);
  http::async_write_header(stream_, *stream_serializer_,
                           [self = shared_from_this()](beast::error_code ec, std::size_t) {
                             self->stream_writing_ = false;
                             if (ec) return self->stream_failed(ec);
                             self->stream_pump();
                           });
}

void HttpSession::stream_pump() {
  if (stream_writing_ || stream_dead_ || !stream_head_) return;
  if (stream_queue_.empty()) {
    auto waiting = std::move(stream_drained_);
    stream_drained_.clear();
    for (auto& f : waiting) f();
    return;
  }
  StreamItem& item = stream_queue_.front();
  auto self = shared_from_this();
  stream_writing_ = true;
  stream_.expires_after(limits::kHttpWriteTimeout);
  if (item.abort) {  // the body cannot be finished: the client sees it cut short
    stream_dead_ = true;
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
    stream_.close();
    return;
  }
  if (item.last) {
    const bool keep = stream_chunked_ && stream_head_->keep_alive();
    auto done = [self, keep](beast::error_code ec, std::size_t) {
      self->stream_writing_ = false;
      self->stream_queue_.clear();
      self->stream_head_.reset();
      if (ec) return self->stream_failed(ec);
      if (keep) return self->read();
      self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    };
    if (stream_chunked_) return asio::async_write(stream_, http::make_chunk_last(), done);
    return done({}, 0);
  }
  auto done = [self](beast::error_code ec, std::size_t) {
    self->stream_writing_ = false;
    self->stream_queued_->fetch_sub(self->stream_queue_.front().bytes.size());
    self->stream_queue_.pop_front();
    if (ec) return self->stream_failed(ec);
    self->stream_pump();
  };
  if (stream_chunked_) return asio::async_write(stream_, http::make_chunk(asio::buffer(item.bytes)), done);
  asio::async_write(stream_, asio::buffer(item.bytes), done);
}

// The client went away (or stopped reading past the write timeout): the producer is told through
// the request's `cancelled`, and whoever waits for the queue to drain is called now.
void HttpSession::stream_failed(beast::error_code ec) {
  fail(ec, "http stream");
  stream_dead_ = true;
  if (stream_cancelled_) stream_cancelled_->store(true);
  app_.render.notify();
  stream_queue_.clear();
  stream_queued_->store(0);
  auto waiting = std::move(stream_drained_);
  stream_drained_.clear();
  for (auto& f : waiting) f();
  beast::error_code ignored;
  stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
}

}  // namespace peakcast::net
