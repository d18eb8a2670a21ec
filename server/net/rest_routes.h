// REST (docs/rest.md): /api/health, /api/volumes, /api/volumes/{id}, POST /api/render, /metrics,
// and client-web/ as static files. Responses are produced through `send`, possibly later (render).
#pragma once

#include <boost/beast/http.hpp>
#include <atomic>
#include <functional>
#include <memory>

#include "net/app_context.h"
#include "net/response_stream.h"

namespace peakcast::net {

namespace http = boost::beast::http;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;

Response json_response(const Request& req, http::status status, const std::string& body);
Response error_response(const Request& req, http::status status, const std::string& code, const std::string& message);
// Counts a request in peakcast_http_requests_total{route, code}.
void count(AppContext& app, const char* route, http::status status);

// Calls `send` exactly once, on any thread (the caller re-posts onto its strand), or, for a
// response streamed as it is made (POST /api/movie), calls `open_stream` on the caller's strand
// and answers through that instead. `cancelled` is set by the connection when its client goes
// away before the answer: a queued or rendering still then stops (at the next band) and its
// answer is dropped.
using OpenStream = std::function<std::shared_ptr<ResponseStream>()>;
void handle_request(AppContext& app, Request req, std::function<void(Response)> send,
                    std::shared_ptr<std::atomic<bool>> cancelled = std::make_shared<std::atomic<bool>>(false),
                    OpenStream open_stream = nullptr);

}  // namespace peakcast::net
