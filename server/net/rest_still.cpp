#include "net/rest_still.h"

#include <bit>
#include <cstdio>

#include <boost/asio/post.hpp>

#include "distributed/brick_sequence.h"
#include "reference/reference_renderer.h"
#include "session/limits.h"

namespace asio = boost::asio;

namespace peakcast::net {
namespace {

// Answers 422 when the still's estimated samples exceed the server's cost cap; true when it did.
bool refused_for_cost(AppContext& app, const Request& req, const ResolvedScene& scene,
                      const std::function<void(Response)>& send) {
  const std::string why = still_cost_refusal(app, scene);
  if (why.empty()) return false;
  count(app, "render", http::status::unprocessable_entity);
  app.metrics.add("peakcast_stills_total", "outcome=\"refused_cost\"", 1);
  send(error_response(req, http::status::unprocessable_entity, "too_costly", why));
  return true;
}

// Reads the image format (?format=, else the Accept header) and ?quality= into the job; false when it
// answered 400 instead.
bool read_still_format(AppContext& app, const Request& req, StillJob& job, const std::function<void(Response)>& send) {
  const std::string format = query_param(std::string(req.target()), "format");
  const std::string accept(req[http::field::accept]);
  if (!format.empty() && format != "png" && format != "jpeg" && format != "jpg" && format != "rgb" &&
      format != "rgba" && format != "float") {
    count(app, "render", http::status::bad_request);
    send(error_response(req, http::status::bad_request, "bad_request",
                        "format must be png, jpeg, rgb, rgba, float or depth"));
    return false;
  }
  job.raw_rgb = format == "rgb";      // packed 8-bit RGB rows from the top: what a script puts in an array
  job.rgba = format == "rgba";        // a PNG with alpha, the background taken out
  job.raw_float = format == "float";  // float32 RGBA as drawn: rows from the top, X-Width x X-Height
  job.png = !(format == "jpeg" || format == "jpg" ||
              (format.empty() && accept.find("image/jpeg") != std::string::npos &&
               accept.find("image/png") == std::string::npos));
  const std::string q = query_param(std::string(req.target()), "quality");
  if (!q.empty()) {
    try {
      job.quality = std::stoi(q);
    } catch (...) {
      job.quality = -1;
    }
    if (job.quality < limits::kMinJpegQuality || job.quality > limits::kMaxJpegQuality) {
      count(app, "render", http::status::bad_request);
      send(error_response(req, http::status::bad_request, "bad_request",
                          "quality must be " + std::to_string(limits::kMinJpegQuality) + ".." +
                              std::to_string(limits::kMaxJpegQuality)));
      return false;
    }
  }
  return true;
}

// The still's answer once drawn: the image with its timings and the scene's warnings, or the
// render's error. `level`: the pyramid level drawn.
std::function<void(StillResult)> still_reply(AppContext& app, const Request& req, const ResolvedScene& scene, int level,
                                             std::function<void(Response)> send) {
  const unsigned version = req.version();
  const bool keep_alive = req.keep_alive();
  // Of the scene: whether its TF was derived, and what it asks for that it will not get.
  const std::string tf_source = scene.tf_derived ? "auto" : "scene";
  const std::vector<std::string> warnings = scene.warnings;
  const int64_t time = scene.scene.time;
  return [&app, send = std::move(send), version, keep_alive, tf_source, warnings, level, time](StillResult r) {
    if (!r.error.empty()) {
      const auto status = r.error_code == "shutting_down" || r.error_code == "cancelled"
                              ? http::status::service_unavailable
                              : http::status::internal_server_error;
      count(app, "render", status);
      Request fake;
      fake.version(version);
      fake.keep_alive(false);
      return send(error_response(fake, status, r.error_code.empty() ? "render_failed" : r.error_code, r.error));
    }
    Response res{http::status::ok, version};
    res.set(http::field::content_type, r.content_type);
    res.set("X-Render-Ms", std::to_string(r.render_ms));
    res.set("X-Encode-Ms", std::to_string(r.encode_ms));
    res.set("X-Samples-Per-Ray", std::to_string(r.samples_per_ray));
    res.set("X-Variant", r.variant);
    res.set("X-Wait-Ms", std::to_string(r.wait_ms));
    res.set("X-Bands", std::to_string(r.bands));
    res.set("X-Level", std::to_string(level));  // the pyramid level drawn (0: the finest)
    if (r.bricks > 0) res.set("X-Bricks", std::to_string(r.bricks));
    res.set("X-TF-Source", tf_source);
    for (const char* name : {"X-Image-Width", "X-Width"}) res.set(name, std::to_string(r.width));
    for (const char* name : {"X-Image-Height", "X-Height"}) res.set(name, std::to_string(r.height));
    res.set("X-Time", std::to_string(time));  // the time point drawn
    for (const std::string& w : warnings) res.insert("X-Warning", w);
    for (const std::string& w : r.warnings) res.insert("X-Warning", w);
    res.body().assign(r.bytes.begin(), r.bytes.end());
    res.keep_alive(keep_alive);
    res.prepare_payload();
    count(app, "render", http::status::ok);
    send(std::move(res));
  };
}

// Answers 503 for a still the render thread would not queue: the server is shutting down, or the
// queue is full.
void refuse_queued_still(AppContext& app, const Request& req, const std::function<void(Response)>& send) {
  const bool stopping = app.stopping.load();
  count(app, "render", http::status::service_unavailable);
  app.metrics.add("peakcast_stills_total", stopping ? "outcome=\"shutting_down\"" : "outcome=\"refused_queue\"", 1);
  auto res =
      stopping ? error_response(req, http::status::service_unavailable, "shutting_down", "the server is shutting down")
               : error_response(req, http::status::service_unavailable, "queue_full",
                                "the still queue holds its maximum of " + std::to_string(app.config.max_queued_stills) +
                                    " renders (max_queued_stills); retry later");
  res.set(http::field::retry_after, std::to_string(limits::kStillRetryAfter.count()));
  send(std::move(res));
}

// The scene is valid and its volume loaded: resolve, queue on the render thread, answer later.
// `full`: the finest level's statistics, for a pyramid held coarser (drawn by bricks).
void submit_still(AppContext& app, const Request& req, const Scene& scene, std::shared_ptr<VolumeEntry> vol,
                  std::function<void(Response)> send, std::shared_ptr<std::atomic<bool>> cancelled,
                  std::shared_ptr<const distributed::SequenceStatistics> full = nullptr) {
  StillJob job;
  job.cancelled = std::move(cancelled);
  const int level = full ? 0 : vol->volume->pyramid_level;
  try {
    job.scene = full ? resolve_scene(scene, full->box) : resolve_scene(scene, *vol->volume);
    job.full_statistics = std::move(full);
  } catch (const SceneError& e) {
    count(app, "render", http::status::bad_request);
    return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
  }
  if (refused_for_cost(app, req, job.scene, send)) return;
  if (!read_still_format(app, req, job, send)) return;
  job.volume = std::move(vol);
  job.done = still_reply(app, req, job.scene, level, send);
  if (!app.render.submit_still(std::move(job))) refuse_queued_still(app, req, send);
}

// ?format=depth: per pixel, the distance from the eye (the image plane for orthographic views)
// to where the ray's opacity first passes one half, the probe's rule; NaN where it never does.
// float32 little-endian, rows from the top. The reference ray on the loader pool, at the level
// held for a pyramid (its voxels are in memory), not on the render thread.
void depth_still(AppContext& app, const Request& req, Scene scene, std::function<void(Response)> send) {
  asio::post(app.loader, [&app, req, scene, send = std::move(send)]() mutable {
    auto refuse = [&](http::status status, const char* code, const std::string& message) {
      count(app, "render", status);
      send(error_response(req, status, code, message));
    };
    try {
      scene.render.ray_texture = load_ray_texture_png(scene.render.ray_texture, app.png_locator());
      const auto vol = app.volumes.at_time(scene.volume, scene.time);
      if (app.config.ranks > 1 || !vol->volume->has_voxels())
        return refuse(http::status::unprocessable_entity, "not_supported",
                      "a depth image needs the volume's voxels; under mpirun they live in the ranks' bricks");
      const ResolvedScene r = resolve_scene(scene, *vol->volume);
      if (refused_for_cost(app, req, r, send)) return;
      const std::vector<float> depth = reference::depth_reference(*vol->volume, r);
      static_assert(std::endian::native == std::endian::little, "the depth image's bytes are little-endian");
      Response res{http::status::ok, req.version()};
      res.set(http::field::content_type, "application/octet-stream");
      for (const char* name : {"X-Width", "X-Image-Width"}) res.set(name, std::to_string(r.scene.width));
      for (const char* name : {"X-Height", "X-Image-Height"}) res.set(name, std::to_string(r.scene.height));
      res.set("X-Level", std::to_string(vol->volume->pyramid_level));
      res.set("X-Time", std::to_string(scene.time));
      res.set("X-TF-Source", r.tf_derived ? "auto" : "scene");
      for (const std::string& w : r.warnings) res.insert("X-Warning", w);
      res.body().assign(reinterpret_cast<const char*>(depth.data()), depth.size() * sizeof(float));
      res.keep_alive(req.keep_alive());
      res.prepare_payload();
      count(app, "render", http::status::ok);
      send(std::move(res));
    } catch (const SceneError& e) {
      refuse(http::status::bad_request, "bad_scene", e.what());
    } catch (const VolumeError& e) {
      refuse(http::status::not_found, "volume_error", e.what());
    } catch (const std::exception& e) {
      refuse(http::status::internal_server_error, "internal", e.what());
    }
  });
}

}  // namespace

// The cost cap: a still whose estimated samples exceed it would hold the render thread for
// minutes; refused before it queues, naming the limit.
std::string still_cost_refusal(const AppContext& app, const ResolvedScene& scene) {
  const double cost = estimated_still_samples(scene);
  if (cost <= app.config.max_still_samples) return "";
  char text[256];
  std::snprintf(text, sizeof text,
                "this still needs about %.3g samples (%d x %d pixels x %.0f samples per ray); the server's limit "
                "max_still_samples is %.3g: use a smaller image or a larger render.step",
                cost, scene.scene.width, scene.scene.height, estimated_samples_per_ray(scene),
                app.config.max_still_samples);
  return text;
}

std::string without_volume_path(const VolumeEntry& entry, std::string message) {
  const std::string from = entry.path.string();
  for (size_t at = 0; !from.empty() && (at = message.find(from, at)) != std::string::npos; at += entry.id.size())
    message.replace(at, from.size(), entry.id);
  return message;
}

void render_still(AppContext& app, const Request& req, std::function<void(Response)> send,
                  std::shared_ptr<std::atomic<bool>> cancelled) {
  Scene scene;
  try {
    scene = parse_scene_text(req.body());
  } catch (const SceneError& e) {
    count(app, "render", http::status::bad_request);
    return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
  }
  if (query_param(std::string(req.target()), "format") == "depth") return depth_still(app, req, scene, std::move(send));
  const bool png = scene.render.ray_texture && !scene.render.ray_texture->png.empty();
  // A pyramid held coarser than its finest level draws the finest by bricks, unless the script
  // asks for the level held (?resolution=held, a quick look).
  const std::string resolution = query_param(std::string(req.target()), "resolution");
  if (!resolution.empty() && resolution != "full" && resolution != "held") {
    count(app, "render", http::status::bad_request);
    return send(error_response(req, http::status::bad_request, "bad_request", "resolution must be full or held"));
  }
  const bool finest = resolution != "held";
  if (auto vol = app.volumes.find_time(scene.volume, scene.time); vol && !png) {
    if (!(vol->full && finest))
      return submit_still(app, req, scene, std::move(vol), std::move(send), std::move(cancelled));
    if (auto known = vol->full->statistics())  // reduced before: no wait
      return submit_still(app, req, scene, std::move(vol), std::move(send), std::move(cancelled), std::move(known));
  }
  // A volume not loaded yet, or a ray-texture PNG: read on the loader pool, never on this io thread.
  asio::post(app.loader, [&app, req, scene, finest, send = std::move(send), cancelled]() mutable {
    try {
      scene.render.ray_texture = load_ray_texture_png(scene.render.ray_texture, app.png_locator());
    } catch (const SceneError& e) {
      count(app, "render", http::status::bad_request);
      return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
    } catch (const std::exception& e) {  // nothing escapes a loader-pool handler
      count(app, "render", http::status::internal_server_error);
      return send(error_response(req, http::status::internal_server_error, "internal", e.what()));
    }
    std::shared_ptr<VolumeEntry> vol;
    try {
      vol = app.volumes.at_time(scene.volume, scene.time);
    } catch (const SceneError& e) {  // a time point past the series' last
      count(app, "render", http::status::bad_request);
      return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
    } catch (const VolumeError& e) {
      count(app, "render", http::status::not_found);
      return send(error_response(req, http::status::not_found, "volume_error", e.what()));
    } catch (const std::exception& e) {  // e.g. out of memory: an answer, never std::terminate
      count(app, "render", http::status::internal_server_error);
      return send(error_response(req, http::status::internal_server_error, "internal", e.what()));
    }
    if (!(vol->full && finest)) return submit_still(app, req, scene, std::move(vol), send, cancelled);
    // The first still of this pyramid's finest level reduces its statistics by bricks: minutes for
    // terabytes, so on the pyramid pool, which holds up no other load.
    asio::post(app.pyramid, [&app, req, scene, vol, send, cancelled]() mutable {
      std::shared_ptr<const distributed::SequenceStatistics> full;
      try {
        full = VolumeStore::full_statistics(*vol, app.stopping);
      } catch (const std::exception& e) {
        count(app, "render", http::status::internal_server_error);
        return send(error_response(req, http::status::internal_server_error, "volume_error",
                                   without_volume_path(*vol, e.what())));
      }
      submit_still(app, req, scene, std::move(vol), send, cancelled, std::move(full));
    });
  });
}

}  // namespace peakcast::net
