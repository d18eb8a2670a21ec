#include "net/rest_routes.h"
#include "net/rest_still.h"
#include "net/rest_slice.h"
#include "net/rest_movie.h"

#include <cstdio>
#include <cstring>

#include <boost/asio/post.hpp>

#include "reference/reference_renderer.h"
#include "render/variant.h"
#include "session/data_listing.h"
#include "session/protocol.h"
#include "session/limits.h"
#include "core/colormaps.h"
#include "core/public_text.h"
#include "core/utf8.h"
#include "net/ws_session.h"

namespace fs = std::filesystem;
namespace asio = boost::asio;

namespace peakcast::net {

void count(AppContext& app, const char* route, http::status status) {
  app.metrics.add("peakcast_http_requests_total",
                  std::string("route=\"") + route + "\",code=\"" + std::to_string(int(status)) + "\"", 1);
}

namespace {

// A file of the fixed list (net/static_files.h), or 404: a URL path is never joined to a root.
Response static_file(AppContext& app, const Request& req, const std::string& path) {
  const auto file = app.files.find(path);
  auto body = file ? StaticFiles::read(*file) : std::nullopt;
  if (!body) return error_response(req, http::status::not_found, "not_found", path + " not found");
  Response res{http::status::ok, req.version()};
  res.set(http::field::content_type, mime_type(path == "/" ? "/index.html" : path));
  res.set(http::field::cache_control, "no-cache");
  res.set("X-Content-Type-Options", "nosniff");
  res.body() = std::move(*body);
  res.keep_alive(req.keep_alive());
  res.prepare_payload();
  return res;
}

// POST /api/probe: a scene plus "pixel": [x, y]; what lies under that pixel (docs/rest.md).
void probe(AppContext& app, const Request& req, std::function<void(Response)> send) {
  Scene scene;
  int x = 0, y = 0;
  reference::ProbePick pick = reference::ProbePick::Surface;
  try {
    nlohmann::json body = nlohmann::json::parse(req.body());
    if (!body.is_object()) throw SceneError("the body must be a JSON object: a scene plus \"pixel\": [x, y]");
    if (!body.contains("pixel")) throw SceneError("pixel: required, [x, y] counted from the image's top left");
    std::tie(x, y) = protocol::parse_pixel(body["pixel"], "pixel");
    body.erase("pixel");
    pick = reference::parse_probe_pick(protocol::parse_pick(body, "pick"));
    body.erase("pick");
    scene = parse_scene(body);
  } catch (const std::exception& e) {  // not JSON, a bad pixel, a bad scene
    count(app, "probe", http::status::bad_request);
    return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
  }
  // Loading the volume, reading a PNG and the ray itself: on the loader pool, never this io thread.
  asio::post(app.loader, [&app, req, scene, x, y, pick, send = std::move(send)]() mutable {
    auto refuse = [&](http::status status, const char* code, const std::string& message) {
      count(app, "probe", status);
      send(error_response(req, status, code, message));
    };
    std::shared_ptr<VolumeEntry> vol;
    try {
      scene.render.ray_texture = load_ray_texture_png(scene.render.ray_texture, app.png_locator());
      vol = app.volumes.at_time(scene.volume, scene.time);
    } catch (const SceneError& e) {
      return refuse(http::status::bad_request, "bad_scene", e.what());
    } catch (const VolumeError& e) {
      return refuse(http::status::not_found, "volume_error", e.what());
    } catch (const std::exception& e) {
      return refuse(http::status::internal_server_error, "internal", e.what());
    }
    try {
      const ResolvedScene resolved = resolve_scene(scene, *vol->volume);
      if (app.config.ranks > 1 || !vol->volume->has_voxels())  // rank 0 holds no voxels (checked before any read)
        return refuse(http::status::unprocessable_entity, "not_supported",
                      "probing needs the volume's voxels; under mpirun they live in the ranks' bricks");
      const auto p = reference::probe_reference(*vol->volume, resolved, x, y, pick);
      count(app, "probe", http::status::ok);
      send(json_response(req, http::status::ok,
                         json_text(protocol::probe_json(p.hit, p.position, p.value, p.distance, p.opacity,
                                                        reference::to_string(p.pick)))));
    } catch (const SceneError& e) {
      refuse(http::status::bad_request, "bad_scene", e.what());
    } catch (const std::invalid_argument& e) {  // the pixel is outside the image
      refuse(http::status::bad_request, "bad_scene", e.what());
    } catch (const std::exception& e) {
      refuse(http::status::internal_server_error, "internal", e.what());
    }
  });
}

// GET /api/colormaps: the named maps' sRGB stops, evenly spaced over [0, 1].
Response colormap_list(AppContext& app, const Request& req) {
  nlohmann::json maps = nlohmann::json::object();
  for (const Colormap& m : colormaps()) {
    nlohmann::json& stops = maps[m.name] = nlohmann::json::array();
    for (const auto& c : m.stops) stops.push_back({c[0] / 255.0, c[1] / 255.0, c[2] / 255.0});
  }
  count(app, "colormaps", http::status::ok);
  return json_response(req, http::status::ok, json_text(nlohmann::json{{"colormaps", maps}}));
}

// POST /api/tf: a scene; the TF it is drawn with (the one derived from the histogram when it
// has none), to edit and send back (docs/rest.md).
void resolved_tf(AppContext& app, const Request& req, std::function<void(Response)> send) {
  Scene scene;
  try {
    scene = parse_scene(nlohmann::json::parse(req.body()));
  } catch (const std::exception& e) {
    count(app, "tf", http::status::bad_request);
    return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
  }
  asio::post(app.loader, [&app, req, scene, send = std::move(send)]() mutable {
    try {
      const auto vol = app.volumes.at_time(scene.volume, scene.time);
      const ResolvedScene r = resolve_scene(scene, *vol->volume);
      Scene drawn = r.scene;
      drawn.tf = r.tf;
      drawn.opacity_unit = r.tf.opacity_unit;
      const nlohmann::json answer = {{"tf", scene_to_json(drawn)["tf"]},
                                     {"tf_source", r.tf_derived ? "auto" : "scene"},
                                     {"range", {vol->volume->min_value, vol->volume->max_value}}};
      count(app, "tf", http::status::ok);
      send(json_response(req, http::status::ok, json_text(answer)));
    } catch (const SceneError& e) {
      count(app, "tf", http::status::bad_request);
      send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
    } catch (const VolumeError& e) {
      count(app, "tf", http::status::not_found);
      send(error_response(req, http::status::not_found, "volume_error", e.what()));
    } catch (const std::exception& e) {
      count(app, "tf", http::status::internal_server_error);
      send(error_response(req, http::status::internal_server_error, "internal", e.what()));
    }
  });
}

// DELETE /api/volumes/{id}: an upload, by its owner or the admin (docs/rest.md, Upload ownership).
// Off the io thread: removing a large file takes a while on some file systems.
void delete_upload(AppContext& app, const Request& req, const std::string& id, const Principal& who,
                   std::function<void(Response)> send) {
  asio::post(app.loader, [&app, req, id, who, send = std::move(send)] {
    try {
      app.uploads.remove(id, app.access.required() && !who.admin ? std::optional<std::string>(who.name) : std::nullopt);
      // Viewers of it move to the default volume: its memory goes with the last of them.
      for (const auto& ws : app.ws_sessions.live()) ws->volume_removed(id);
      count(app, "delete", http::status::ok);
      send(json_response(req, http::status::ok, json_text(nlohmann::json{{"deleted", id}})));
    } catch (const UploadRefusal& r) {
      count(app, "delete", http::status(r.status));
      send(error_response(req, http::status(r.status), r.code, r.what()));
    } catch (const std::exception& e) {
      count(app, "delete", http::status::internal_server_error);
      send(error_response(req, http::status::internal_server_error, "internal", e.what()));
    }
  });
}

// GET /api/files?dir=: the data-directory browser, one folder, relative names only. On its own
// thread: no volume load holds a listing up.
void list_files(AppContext& app, const Request& req, std::function<void(Response)> send) {
  const std::string dir = url_decode(query_param(std::string(req.target()), "dir"));
  asio::post(app.listing, [&app, req, dir, send = std::move(send)] {
    try {
      auto list = list_data_dir(app.volumes.data_dirs(), dir);
      count(app, "files", http::status::ok);
      send(json_response(req, http::status::ok, json_text(list)));
    } catch (const VolumeError& e) {
      count(app, "files", http::status::not_found);
      send(error_response(req, http::status::not_found, "not_found", e.what()));
    } catch (const std::exception& e) {
      count(app, "files", http::status::internal_server_error);
      send(error_response(req, http::status::internal_server_error, "internal", e.what()));
    }
  });
}

// POST /api/render: a still (net/rest_still.h), unless the method is wrong or the server stops.
void render_route(AppContext& app, const Request& req, std::function<void(Response)> send,
                  std::shared_ptr<std::atomic<bool>> cancelled) {
  if (req.method() != http::verb::post)
    return send(error_response(req, http::status::method_not_allowed, "bad_request", "POST a scene"));
  if (app.stopping.load()) {
    auto res = error_response(req, http::status::service_unavailable, "shutting_down", "the server is shutting down");
    res.set(http::field::retry_after, std::to_string(limits::kStillRetryAfter.count()));
    return send(std::move(res));
  }
  render_still(app, req, std::move(send), std::move(cancelled));
}

// GET /api/health: open to all (docs/security.md, "Not covered").
Response health(AppContext& app, const Request& req) {
  const bool stopping = app.stopping.load();
  const auto status = stopping ? http::status::service_unavailable : http::status::ok;
  count(app, "health", status);
  const auto& uploads = app.uploads.limits();
  return json_response(req, status,
                       json_text(nlohmann::json{{"status", stopping ? "stopping" : "ok"},
                                                {"gl_renderer", app.render.gl_renderer()},
                                                {"backend", app.render.backend()},
                                                {"ranks", app.render.ranks()},
                                                {"sessions", app.ws_sessions.count()},
                                                {"max_sessions", app.config.max_sessions},
                                                {"volumes", app.volumes.list().size()},
                                                {"volume_bytes", app.residency.counted_bytes()},
                                                {"stills_queued", app.render.stills_pending()},
                                                {"still_progress", app.render.still_progress()},
                                                {"max_queued_stills", app.config.max_queued_stills},
                                                {"uploads",
                                                 {{"enabled", app.uploads.enabled()},
                                                  {"max_bytes", uploads.max_bytes},
                                                  {"budget_bytes", uploads.budget_bytes},
                                                  {"used_bytes", app.uploads.used_bytes()}}}}));
}

}  // namespace

Response json_response(const Request& req, http::status status, const std::string& body) {
  Response res{status, req.version()};
  res.set(http::field::content_type, "application/json");
  res.set(http::field::cache_control, "no-store");
  res.body() = body;
  res.keep_alive(req.keep_alive());
  res.prepare_payload();
  return res;
}

// Whatever the message holds (a client's bytes, a library's path), the answer is UTF-8 JSON with
// no server path (core/public_text.h), and building it cannot throw for bad bytes.
Response error_response(const Request& req, http::status status, const std::string& code, const std::string& message) {
  return json_response(req, status, json_text(nlohmann::json{{"error", code}, {"message", public_text(message)}}));
}

void handle_request(AppContext& app, Request req, std::function<void(Response)> send,
                    std::shared_ptr<std::atomic<bool>> cancelled, OpenStream open_stream) {
  const std::string path = path_of(std::string(req.target()));
  const bool api = path.rfind("/api/", 0) == 0 || path == "/metrics";
  const Principal who =
      app.access.who(token_from(std::string(req[http::field::authorization]), std::string(req.target())));
  if (api && path != "/api/health" && !who.authorized) {
    count(app, "auth", http::status::unauthorized);
    auto res = error_response(req, http::status::unauthorized, "unauthorized", "missing or wrong bearer token");
    res.set(http::field::www_authenticate, "Bearer");
    return send(std::move(res));
  }
  if (path == "/api/render") return render_route(app, req, std::move(send), std::move(cancelled));
  if (path == "/api/movie") return movie(app, req, std::move(send), std::move(cancelled), std::move(open_stream));
  if (path == "/api/probe") {
    if (req.method() != http::verb::post)
      return send(
          error_response(req, http::status::method_not_allowed, "bad_request", "POST a scene with \"pixel\": [x, y]"));
    return probe(app, req, std::move(send));
  }
  if (path == "/api/slice") return slice_still(app, req, std::move(send));  // POST only: it says so
  if (path == "/api/tf") {
    if (req.method() != http::verb::post)
      return send(error_response(req, http::status::method_not_allowed, "bad_request", "POST a scene"));
    return resolved_tf(app, req, std::move(send));
  }
  if (req.method() == http::verb::delete_ && path.rfind("/api/volumes/", 0) == 0)
    return delete_upload(app, req, url_decode(path.substr(std::strlen("/api/volumes/"))), who, std::move(send));
  if (req.method() != http::verb::get && req.method() != http::verb::head)
    return send(
        error_response(req, http::status::method_not_allowed, "bad_request",
                       path.rfind("/api/volumes", 0) == 0 ? "GET, POST an upload, or DELETE an upload" : "GET only"));
  if (path == "/api/health") return send(health(app, req));
  if (path == "/api/files") return list_files(app, req, std::move(send));
  if (path == "/api/colormaps") return send(colormap_list(app, req));
  if (path == "/api/volumes") {
    const nlohmann::json list = app.volumes.listing();
    count(app, "volumes", http::status::ok);
    return send(json_response(req, http::status::ok,
                              json_text(nlohmann::json{{"volumes", list}, {"default", app.volumes.default_id()}})));
  }
  if (path.rfind("/api/volumes/", 0) == 0) {
    const std::string id = url_decode(path.substr(std::strlen("/api/volumes/")));
    auto v = app.volumes.find(id);
    if (!v && app.volumes.known(id))  // an upload listed since a restart, read when first asked for
      return asio::post(app.loader, [&app, req, id, send = std::move(send)] {
        try {
          auto e = app.volumes.get(id);
          count(app, "volume", http::status::ok);
          send(json_response(req, http::status::ok, json_text(e->info(true))));
        } catch (const std::exception& e) {
          count(app, "volume", http::status::internal_server_error);
          send(error_response(req, http::status::internal_server_error, "volume_error", e.what()));
        }
      });
    count(app, "volume", v ? http::status::ok : http::status::not_found);
    if (!v) return send(error_response(req, http::status::not_found, "not_found", "no loaded volume '" + id + "'"));
    return send(json_response(req, http::status::ok, json_text(v->info(true))));
  }
  if (path == "/metrics") {
    app.metrics.set("peakcast_sessions", "", app.ws_sessions.count());
    app.metrics.set("peakcast_connections", "", app.connections.open());
    Response res{http::status::ok, req.version()};
    res.set(http::field::content_type, "text/plain; version=0.0.4");
    res.body() = app.metrics.prometheus_text();
    res.keep_alive(req.keep_alive());
    res.prepare_payload();
    return send(std::move(res));
  }
  if (api) return send(error_response(req, http::status::not_found, "not_found", path + " is not an API route"));
  // The docs the client's help links to (docs/ beside client-web/, in the container too).
  send(static_file(app, req, path));
}

}  // namespace peakcast::net
