// Chunked uploads (docs/rest.md, "Chunked uploads"; session/chunked_upload.h): POST /api/uploads
// declares an array, PUT /api/uploads/{id}/chunks/{i}/{j}/{k} sends a chunk, GET /api/uploads/{id}
// says what arrived and how the build goes, POST /api/uploads/{id}/finish builds the pyramid,
// DELETE /api/uploads/{id} removes an upload not yet built. Chunk writes run on their own pool,
// builds on theirs: neither holds an io thread nor a volume load.
#include "net/rest_uploads.h"

#include <cstring>

#include <boost/asio/post.hpp>

#include "core/utf8.h"

namespace asio = boost::asio;

namespace peakcast::net {
namespace {

void answer(AppContext& app, const Request& req, const std::function<void(Response)>& send, http::status status,
            const nlohmann::json& body) {
  count(app, "uploads", status);
  send(json_response(req, status, json_text(body)));
}

void refuse(AppContext& app, const Request& req, const std::function<void(Response)>& send, const UploadRefusal& r) {
  count(app, "uploads", http::status(r.status));
  auto res = error_response(req, http::status(r.status), r.code, r.what());
  if (r.retry_after_s > 0) res.set(http::field::retry_after, std::to_string(r.retry_after_s));
  send(std::move(res));
}

// Runs `work` (which answers with a JSON body and `ok`, or throws UploadRefusal) and answers.
template <class Work>
void run(AppContext& app, const Request& req, const std::function<void(Response)>& send, http::status ok, Work work) {
  try {
    answer(app, req, send, ok, work());
  } catch (const UploadRefusal& r) {
    refuse(app, req, send, r);
  } catch (const nlohmann::json::exception& e) {
    refuse(app, req, send, UploadRefusal(400, "bad_upload", std::string("the body is not valid JSON: ") + e.what()));
  } catch (const std::exception& e) {
    refuse(app, req, send, UploadRefusal(500, "internal", e.what()));
  }
}

// "/api/uploads/{id}/chunks/{i}/{j}/{k}" -> the index; false when the path is not that.
bool chunk_index(const std::vector<std::string>& parts, std::array<int64_t, 3>& index) {
  if (parts.size() != 5 || parts[1] != "chunks") return false;
  for (int a = 0; a < 3; ++a) {
    const std::string& p = parts[size_t(a) + 2];
    if (p.empty() || p.size() > 9 || p.find_first_not_of("0123456789") != std::string::npos) return false;
    index[a] = std::stoll(p);
  }
  return true;
}

std::vector<std::string> split_path(const std::string& rest) {
  std::vector<std::string> parts;
  size_t at = 0;
  while (at <= rest.size()) {
    const size_t slash = std::min(rest.find('/', at), rest.size());
    parts.push_back(url_decode(rest.substr(at, slash - at)));
    at = slash + 1;
  }
  return parts;
}

}  // namespace

void uploads_route(AppContext& app, Request req, const std::string& client, std::function<void(Response)> send) {
  const std::string path = path_of(std::string(req.target()));
  const Principal who =
      app.access.who(token_from(std::string(req[http::field::authorization]), std::string(req.target())));
  if (!who.authorized) {
    count(app, "auth", http::status::unauthorized);
    auto res = error_response(req, http::status::unauthorized, "unauthorized", "missing or wrong bearer token");
    res.set(http::field::www_authenticate, "Bearer");
    return send(std::move(res));
  }
  const std::optional<std::string> as_owner =
      app.access.required() && !who.admin ? std::optional<std::string>(who.name) : std::nullopt;
  auto& up = app.chunked_uploads;
  const auto verb = req.method();
  if (path == "/api/uploads") {
    if (verb != http::verb::post)
      return send(error_response(req, http::status::method_not_allowed, "bad_request", "POST an array's declaration"));
    return run(app, req, send, http::status::created,
               [&] { return up.begin(client, nlohmann::json::parse(req.body()), who.name); });
  }
  const std::vector<std::string> parts = split_path(path.substr(std::strlen("/api/uploads/")));
  const std::string& id = parts[0];
  std::array<int64_t, 3> index{};
  if (parts.size() == 1 && verb == http::verb::get)
    return run(app, req, send, http::status::ok, [&] { return up.status(id, as_owner); });
  if (parts.size() == 1 && verb == http::verb::delete_)
    return run(app, req, send, http::status::ok, [&] {
      up.remove(id, as_owner);
      return nlohmann::json{{"deleted", id}};
    });
  if (parts.size() == 2 && parts[1] == "finish" && verb == http::verb::post)
    return run(app, req, send, http::status::accepted, [&] {
      up.mark_building(id, as_owner);
      asio::post(app.builds, [&app, id] { app.chunked_uploads.finish(id); });
      return up.status(id, as_owner);
    });
  if (chunk_index(parts, index) && verb == http::verb::put)
    return asio::post(app.chunk_writes, [&app, req = std::move(req), send = std::move(send), id, index, as_owner] {
      run(app, req, send, http::status::ok, [&] { return app.chunked_uploads.put(id, as_owner, index, req.body()); });
    });
  send(error_response(req, http::status::not_found, "not_found",
                      path + ": the routes are POST /api/uploads, GET, DELETE /api/uploads/{id}, PUT "
                             "/api/uploads/{id}/chunks/{i}/{j}/{k} and POST /api/uploads/{id}/finish"));
}

}  // namespace peakcast::net
