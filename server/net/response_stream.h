// A response sent as it is made (POST /api/movie): the header, then the body's bytes in order as
// they come, then the end; chunked transfer encoding for HTTP/1.1, the connection's close for
// 1.0. Every call may come from any thread: the bytes are written on the connection's strand, in
// the order given, and what waits is counted, so a producer can hold back for a slow client.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include <boost/beast/http.hpp>

namespace peakcast::net {

using StreamHeader = boost::beast::http::response<boost::beast::http::empty_body>;

class ResponseStream {
 public:
  virtual ~ResponseStream() = default;
  virtual void begin(StreamHeader header) = 0;  // once, first; the request's send() is not called after
  virtual void write(std::string bytes) = 0;
  virtual void end() = 0;                   // the body is whole (the last chunk)
  virtual void abort() = 0;                 // an error after the header: the connection closes without the last chunk
  virtual size_t queued_bytes() const = 0;  // given to write() and not yet on the socket
  // Called (on the strand) once what is queued has been written, or at once when nothing is; or
  // when the connection failed (the client went away: the request's `cancelled` is set first).
  virtual void when_drained(std::function<void()> f) = 0;
};

}  // namespace peakcast::net
