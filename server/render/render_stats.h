// What one frame (or one tile, or a still assembled from tiles) cost: GPU time, read-back,
// table builds, samples per ray. One JSON form for the CLI (`render --stats`) and the stream's
// stats message (proto/server_messages.schema.json, $defs/stats).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace peakcast {
struct ResolvedScene;
}

namespace peakcast::render {

struct RenderStats {
  double render_ms = 0.0;  // the draw: GL, issued to finished (wall); CPU, the ray cast
  // GL only: the GPU's own time for the draw (a timer query), apart from the frame's waits;
  // < 0 where not measured (the CPU backend, a driver without timer queries).
  double gpu_ms = -1.0;
  // GL only: how long the frame waited for its shader program (0: compiled before, in memory).
  double compile_ms = 0.0;
  double readback_ms = 0.0;  // GPU -> host copy of the output (and the sample counts when read)
  double table_ms = 0.0;     // peak table / preintegration table / occupancy rebuilt for this frame
  // Sample counts are read back for RenderOutput::Float always, for Rgb8 only on request
  // (RenderRequest::sample_stats); without them the samples_* fields and rays_hit are 0 and
  // to_json leaves them out.
  bool has_samples = false;
  double samples_mean = 0.0;  // per ray that hits the box (skipped rays count with 0)
  double samples_max = 0.0;
  double samples_total = 0.0;
  int64_t rays_hit = 0;
  int64_t rays_at_cap = 0;  // rays that reached sample_cap
  int sample_cap = 0;       // the per-ray cap of this frame: kMaxSamplesPerRay, or the driver's
  int64_t empty_cells = 0;
  size_t peaks = 0;
  int tiles = 1;  // draws that made the image (merge() counts them)
  // With a ray texture (a +raytex variant): host time spent applying new strokes and uploading
  // the texels they touched, the strokes applied, and the texels uploaded (0 when unchanged).
  double ray_texture_ms = 0.0;
  int64_t ray_texture_strokes = 0, ray_texture_texels = 0;
  std::string variant;
  // Of the scene, not the frame: "auto" when its TF was derived from the histogram, else
  // "scene"; what it asks for that it will not get (ResolvedScene::warnings).
  std::string tf_source = "scene";
  std::vector<std::string> warnings;

  // Empty stats carrying the scene's part (tf_source, warnings): where every frame starts.
  static RenderStats for_scene(const ResolvedScene& s);

  // Keys: render_ms, readback_ms, table_ms, variant, peaks, empty_macrocells, tiles, tf_source,
  // warnings, compile_ms, gpu_ms (when measured), with a ray
  // texture ray_texture_ms, ray_texture_strokes, ray_texture_texels, and, with
  // sample counts, samples_per_ray, samples_per_ray_max, rays_hit, rays_at_sample_cap. The stream adds its frame
  // keys (type, frame, final, width, height, encode_ms, bytes) to this object.
  nlohmann::json to_json() const;
  // The same keys and values as to_json, as "key=value" pairs in a fixed order.
  std::string to_string() const;
  // Adds a later tile's stats to a tiled image's (start from the first tile's): times, samples
  // and tiles add up, the max is the max; variant, peaks and empty cells are the scene's, the
  // same for every tile. Samples stay only if every tile had them.
  void merge(const RenderStats& tile);
};

}  // namespace peakcast::render
