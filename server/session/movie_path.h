// A movie (POST /api/movie, docs/rest.md "Movies"): a scene, a camera path (an orbit, or key
// frames of camera, TF and time point interpolated between them), the frame count and rate, and
// the encoding. Parsing and the path's arithmetic; rendering and streaming are net/rest_movie.cpp.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "core/scene.h"
#include "encode/movie_writer.h"

namespace peakcast {

// One key frame: what it sets (what it leaves out, it keeps from the key before it; the first
// from the scene).
struct MovieKey {
  std::optional<Camera> camera;
  std::optional<TransferFunction> tf;
  std::optional<int64_t> time;
};

struct MovieRequest {
  Scene scene;
  // "path": {"orbit": {"axis": [x, y, z], "degrees": d}} or {"keys": [...]}.
  bool orbit = true;
  std::optional<glm::dvec3> axis;  // the orbit's axis through the camera's focal point; default: its view up
  double degrees = 360.0;
  std::vector<MovieKey> keys;
  int frames = 60;
  int fps = 30;
  encode::MovieFormat format = encode::MovieFormat::Mp4;
  int quality = 90;  // 10..100, as a JPEG still's (mapped onto the codec's CRF; PNG ignores it)
};

inline constexpr int kMaxMovieFrames = 3600;  // two minutes at 30 frames a second
inline constexpr int kMaxMovieFps = 120;

// Throws SceneError naming the key ("frames: must be in [1, 3600]", "path.keys[2].camera.eye: ...").
MovieRequest parse_movie(const nlohmann::json& body);
MovieRequest parse_movie_text(const std::string& text);

// The scene of every frame, in order: the path applied to `first`, the movie's scene resolved
// against its volume (the camera an orbit turns, the TF key frames start from). An orbit of d
// degrees puts frame i at d i / frames when d is a whole number of turns (the movie loops: its
// last frame is one step short of the first) and at d i / (frames - 1) otherwise (it ends at d).
// Keys are spread evenly over the frames (key k at frame k (frames - 1) / (keys - 1)); between
// two, the focal point, the view angle (or height) and the TF's points move linearly, the eye
// turns about the focal point (its direction interpolated on the sphere, its distance
// geometrically) and the time point is the nearest. Throws SceneError for keys that mix
// perspective and orthographic views.
std::vector<Scene> movie_frames(const MovieRequest& m, const ResolvedScene& first);

// Two TFs blended: every point value of either, each colour and opacity (1 - u) a + u b.
TransferFunction blend_tfs(const TransferFunction& a, const TransferFunction& b, double u);
// Two cameras between their keys (u in [0, 1]), as movie_frames moves them.
Camera blend_cameras(const Camera& a, const Camera& b, double u);

}  // namespace peakcast
