// POST /api/slice (docs/rest.md, "Slices"): a scene plus "slice"; the slice as a PNG, drawn on the
// loader pool from the voxels held (a pyramid: the finest level the memory budget holds).
#include "net/rest_slice.h"

#include "core/slice_view.h"
#include "encode/png.h"
#include "net/beast.h"
#include "net/http_text.h"

namespace peakcast::net {

void slice_still(AppContext& app, const Request& req, std::function<void(Response)> send) {
  if (req.method() != http::verb::post)
    return send(error_response(req, http::status::method_not_allowed, "bad_request",
                               "POST a scene with \"slice\": {\"axis\": \"z\", \"index\": k}"));
  Scene scene;
  SliceRequest slice;
  std::optional<std::array<int, 2>> size;
  try {
    nlohmann::json body = nlohmann::json::parse(req.body());
    if (!body.is_object() || !body.contains("slice"))
      throw SceneError("the body must be a scene plus \"slice\": {\"axis\": \"z\", \"index\": k} or {\"plane\": ...}");
    slice = parse_slice(body["slice"]);
    body.erase("slice");
    const bool sized = body.contains("image");
    scene = parse_scene(body);
    if (sized) size = std::array<int, 2>{scene.width, scene.height};
  } catch (const std::exception& e) {  // not JSON, a bad slice, a bad scene
    count(app, "slice", http::status::bad_request);
    return send(error_response(req, http::status::bad_request, "bad_scene", e.what()));
  }
  asio::post(app.loader, [&app, req, scene, slice, size, send = std::move(send)]() mutable {
    auto refuse = [&](http::status status, const char* code, const std::string& message) {
      count(app, "slice", status);
      send(error_response(req, status, code, message));
    };
    try {
      const auto vol = app.volumes.at_time(scene.volume, scene.time);
      if (app.config.ranks > 1 || !vol->volume->has_voxels())
        return refuse(http::status::unprocessable_entity, "not_supported",
                      "a slice needs the volume's voxels; under mpirun they live in the ranks' bricks");
      scene.render.ray_texture.reset();  // a slice has no rays
      const ResolvedScene r = resolve_scene(scene, *vol->volume);
      const SliceImage img = draw_slice(*vol->volume, r, slice, size);
      const std::vector<unsigned char> png = encode::encode_png(img.rgb.data(), img.width, img.height);
      Response res{http::status::ok, req.version()};
      res.set(http::field::content_type, "image/png");
      res.set("X-Width", std::to_string(img.width));
      res.set("X-Height", std::to_string(img.height));
      res.set("X-Level", std::to_string(vol->volume->pyramid_level));
      if (img.index >= 0) res.set("X-Index", std::to_string(img.index));
      res.set("X-TF-Source", slice.window ? "window" : r.tf_derived ? "auto" : "scene");
      res.body().assign(png.begin(), png.end());
      res.keep_alive(req.keep_alive());
      res.prepare_payload();
      count(app, "slice", http::status::ok);
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

}  // namespace peakcast::net
