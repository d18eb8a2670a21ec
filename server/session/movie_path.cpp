#include "session/movie_path.h"

#include <algorithm>
#include <cmath>
#include <set>

#include <glm/geometric.hpp>

#include "core/json_fields.h"

namespace peakcast {
namespace {

using json = nlohmann::json;
using namespace json_fields;

// Parses one key frame's camera and TF by the scene's own rules, its messages under `where`.
MovieKey parse_key(const json& j, const std::string& volume, const std::string& where) {
  only_keys(j, where, {"camera", "tf", "time"});
  MovieKey key;
  json scene = {{"volume", volume}};
  for (const char* part : {"camera", "tf", "time"})
    if (j.contains(part)) scene[part] = j[part];
  Scene s;
  try {
    s = parse_scene(scene);
  } catch (const SceneError& e) {
    throw SceneError(where + "." + e.what());
  }
  if (s.camera) key.camera = s.camera;
  if (s.tf) {
    key.tf = s.tf;
    key.tf->opacity_unit = s.opacity_unit;
  }
  if (j.contains("time")) key.time = s.time;
  return key;
}

void parse_path(const json& path, MovieRequest& m) {
  if (!path.is_object() || path.size() != 1 || !(path.contains("orbit") || path.contains("keys")))
    fail("path", "must be {\"orbit\": {\"axis\": [x, y, z], \"degrees\": d}} or {\"keys\": [...]}");
  if (path.contains("orbit")) {
    const json& o = path["orbit"];
    only_keys(o, "path.orbit", {"axis", "degrees"});
    if (o.contains("axis")) {
      m.axis = vec3(o["axis"], "path.orbit.axis");
      if (!(glm::length(*m.axis) > 0)) fail("path.orbit.axis", "must not be the zero vector");
    }
    if (o.contains("degrees")) {
      m.degrees = number(o["degrees"], "path.orbit.degrees");
      if (std::abs(m.degrees) > 3600) fail("path.orbit.degrees", "must be in [-3600, 3600] (ten turns)");
    }
    m.orbit = true;
    return;
  }
  const json& keys = path["keys"];
  if (!keys.is_array() || keys.empty()) fail("path.keys", "must be a non-empty array of {camera, tf, time}");
  if (keys.size() > size_t(kMaxMovieFrames)) fail("path.keys", "more keys than frames can show");
  m.orbit = false;
  for (size_t k = 0; k < keys.size(); ++k)
    m.keys.push_back(parse_key(keys[k], m.scene.volume, "path.keys[" + std::to_string(k) + "]"));
}

glm::dvec3 rotate(const glm::dvec3& v, const glm::dvec3& unit_axis, double radians) {
  const double c = std::cos(radians), s = std::sin(radians);  // Rodrigues
  return v * c + glm::cross(unit_axis, v) * s + unit_axis * glm::dot(unit_axis, v) * (1 - c);
}

// The unit vectors a and b interpolated on the sphere (slerp); nearly opposite: about `pole`.
glm::dvec3 slerp(const glm::dvec3& a, const glm::dvec3& b, double u, const glm::dvec3& pole) {
  const double d = std::clamp(glm::dot(a, b), -1.0, 1.0);
  const double angle = std::acos(d);
  if (angle < 1e-9) return a;
  glm::dvec3 axis = glm::cross(a, b);
  if (glm::length(axis) < 1e-9) axis = glm::cross(a, pole);  // opposite: turn through the pole
  if (glm::length(axis) < 1e-9) axis = glm::cross(a, std::abs(a.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0));
  return rotate(a, glm::normalize(axis), angle * u);
}

std::vector<Scene> orbit_frames(const MovieRequest& m, const ResolvedScene& first) {
  const Camera& c = first.camera;
  const glm::dvec3 axis = glm::normalize(m.axis ? *m.axis : c.up);
  const double turns = m.degrees / 360.0;
  const bool loops = m.degrees != 0 && turns == std::round(turns);
  std::vector<Scene> out;
  for (int i = 0; i < m.frames; ++i) {
    const double span = loops ? m.frames : std::max(1, m.frames - 1);
    const double radians = m.degrees * M_PI / 180.0 * double(i) / span;
    Scene s = m.scene;
    Camera cam = c;
    cam.eye = c.center + rotate(c.eye - c.center, axis, radians);
    cam.up = rotate(c.up, axis, radians);
    s.camera = cam;
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

MovieRequest parse_movie(const json& body) {
  if (!body.is_object())
    fail("movie", "the body must be a JSON object: a scene plus \"path\", \"frames\", \"fps\", \"format\"");
  MovieRequest m;
  json scene = body;
  for (const char* k : {"path", "frames", "fps", "format", "quality"}) scene.erase(k);
  m.scene = parse_scene(scene);
  if (body.contains("frames")) m.frames = integer(body["frames"], "frames", 1, kMaxMovieFrames);
  if (body.contains("fps")) m.fps = integer(body["fps"], "fps", 1, kMaxMovieFps);
  if (body.contains("quality")) m.quality = integer(body["quality"], "quality", 10, 100);
  if (body.contains("format")) {
    if (!body["format"].is_string()) fail("format", "must be \"mp4\", \"webm\", \"png-zip\" or \"rgb\"");
    const auto f = encode::movie_format_from_name(body["format"].get<std::string>());
    if (!f) fail("format", "'" + body["format"].get<std::string>() + "' is not one of mp4, webm, png-zip, rgb");
    m.format = *f;
  }
  if (body.contains("path")) parse_path(body["path"], m);
  if (!m.orbit && m.keys.size() > size_t(m.frames))
    fail("path.keys", std::to_string(m.keys.size()) + " keys need at least as many frames (frames is " +
                          std::to_string(m.frames) + ")");
  return m;
}

MovieRequest parse_movie_text(const std::string& text) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw SceneError(std::string("movie is not valid JSON: ") + e.what());
  }
  return parse_movie(j);
}

TransferFunction blend_tfs(const TransferFunction& a, const TransferFunction& b, double u) {
  std::set<double> values;
  for (const TfPoint& p : a.points) values.insert(p.value);
  for (const TfPoint& p : b.points) values.insert(p.value);
  TransferFunction out;
  out.opacity_unit = a.opacity_unit + (b.opacity_unit - a.opacity_unit) * u;
  for (double v : values) {
    const glm::dvec4 c = a.eval(v) * (1 - u) + b.eval(v) * u;
    out.points.push_back({v, c.r, c.g, c.b, c.a});
  }
  return out;
}

Camera blend_cameras(const Camera& a, const Camera& b, double u) {
  if (a.orthographic != b.orthographic)
    throw SceneError(
        "path.keys: one key's camera is perspective and the next's orthographic: a path keeps one projection");
  Camera c = a;
  c.center = a.center + (b.center - a.center) * u;
  const glm::dvec3 da = a.eye - a.center, db = b.eye - b.center;
  const double la = glm::length(da), lb = glm::length(db);
  const glm::dvec3 up_a = glm::normalize(a.up), up_b = glm::normalize(b.up);
  const glm::dvec3 dir = slerp(da / la, db / lb, u, up_a);
  c.eye = c.center + dir * (la * std::pow(lb / la, u));
  const glm::dvec3 up = slerp(up_a, up_b, u, -dir);
  c.up = glm::length(up - dir * glm::dot(up, dir)) > 1e-6 ? up : up_a;
  c.fov_y = a.fov_y + (b.fov_y - a.fov_y) * u;
  c.height = a.height + (b.height - a.height) * u;
  return c;
}

std::vector<Scene> movie_frames(const MovieRequest& m, const ResolvedScene& first) {
  if (m.orbit) return orbit_frames(m, first);
  // Each key complete: what it leaves out, from the key before (the first: the resolved scene).
  std::vector<Camera> cams;
  std::vector<TransferFunction> tfs;
  std::vector<int64_t> times;
  for (const MovieKey& k : m.keys) {
    cams.push_back(k.camera ? *k.camera : cams.empty() ? first.camera : cams.back());
    tfs.push_back(k.tf ? *k.tf : tfs.empty() ? first.tf : tfs.back());
    if (!(tfs.back().opacity_unit > 0)) tfs.back().opacity_unit = first.tf.opacity_unit;  // the volume's default
    times.push_back(k.time ? *k.time : times.empty() ? m.scene.time : times.back());
  }
  std::vector<Scene> out;
  const int keys = int(m.keys.size());
  for (int i = 0; i < m.frames; ++i) {
    const double p = keys == 1 || m.frames == 1 ? 0.0 : double(i) * (keys - 1) / double(m.frames - 1);
    const int k = std::min(int(std::floor(p)), std::max(0, keys - 2));
    const double u = keys == 1 ? 0.0 : p - k;
    const int next = std::min(k + 1, keys - 1);
    Scene s = m.scene;
    s.camera = blend_cameras(cams[k], cams[next], u);
    s.tf = blend_tfs(tfs[k], tfs[next], u);
    s.opacity_unit = s.tf->opacity_unit;
    s.time = std::llround(double(times[k]) + double(times[next] - times[k]) * u);
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace peakcast
