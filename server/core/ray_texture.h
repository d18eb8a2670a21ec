// Ray textures (Raspe & Müller 2008): a per-session 2D map of per-ray controls, painted with
// brush strokes. Channels, one float each per texel:
//   step         multiplier of the ray's step, [1/8, 8], default 1;
//   termination  early-termination opacity, [0, 1], default the scene's;
//   blend        weight between the DVR and the peak contributions, [-1, 1], default 0: b > 0
//                fades the DVR samples' opacity by (1 - b), b < 0 the peaks' by (1 + b).
// Mappings: `view` indexes by window position (u right, v down over the image); `volume` by
// the ray's entry point on the volume box (ray_texture_uv in core/ray_texture_mapping.h), so
// an edit stays on the volume when the camera moves.
// Strokes are the state: a texture is its starting image (defaults, or a PNG) with its strokes
// applied in order. A spec is immutable once made; a painted stroke makes a new spec of the same
// lineage (with_stroke), so a renderer holding the first n strokes applies only the rest.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace peakcast {

enum class RayTextureMapping { View, Volume };
enum class RayChannel { Step = 0, Termination = 1, Blend = 2 };
enum class StrokeMode { Set, Add, Multiply };

struct Stroke {
  RayChannel channel = RayChannel::Step;
  double u = 0.5, v = 0.5;  // centre, texture units [0, 1]
  double radius = 0.1;      // (0, 1], texture units (of the texture's larger side)
  double falloff = 0.0;     // [0, 1]: share of the radius over which the weight falls to 0
  double value = 1.0;
  StrokeMode mode = StrokeMode::Set;
  int level = 0;  // 0: direct; L > 0: edits 2^L x 2^L blocks (Raspe §3.2, hierarchical)
};

// Limits at the edge.
constexpr int kMaxRayTextureSide = 2048;
constexpr size_t kMaxRayTextureStrokes = 100000;
constexpr int kMaxStrokeLevel = 8;
constexpr double kMinStepMultiplier = 1.0 / 8.0, kMaxStepMultiplier = 8.0;
// Texel updates all of a texture's strokes may make (the sum of their bounding boxes): what one
// build of it costs the render thread, bounded (2^28: about half a second on one core).
constexpr uint64_t kMaxRayTextureWork = uint64_t(1) << 28;

// Level-0 texels read from an image (core/ray_texture_png.h): interleaved step, termination,
// blend, row 0 = v 0.
struct RayTextureImage {
  int width = 0, height = 0;
  std::vector<float> texels;
};

struct RayTextureSpec {
  RayTextureMapping mapping = RayTextureMapping::View;
  int width = 256, height = 256;
  std::vector<Stroke> strokes;
  // Instead of size: a PNG whose R, G, B are the channels (core/ray_texture_png.h), resolved like
  // the volume; strokes apply over it. `image` holds its texels once read (null before).
  std::string png;
  std::shared_ptr<const RayTextureImage> image;
  // One edit history: every parse starts a new lineage; with_stroke keeps it.
  uint64_t lineage = 0;
  uint64_t work = 0;  // texel updates of the strokes (stroke_texels), at most kMaxRayTextureWork
};

// Texels a stroke's bounding box covers on a width x height texture (whole blocks at its level).
uint64_t stroke_texels(const Stroke& s, int width, int height);
// The spec's work recounted for its size (a PNG's size is known once read). Throws SceneError
// past kMaxRayTextureWork.
void count_work(RayTextureSpec& spec, const std::string& where = "render.ray_texture.strokes");

// Throws SceneError naming the key (`where`, e.g. "render.ray_texture.strokes[3].radius").
RayTextureSpec parse_ray_texture(const nlohmann::json& j, const std::string& where = "render.ray_texture");
Stroke parse_stroke(const nlohmann::json& j, const std::string& where);
nlohmann::json to_json(const Stroke& s);
nlohmann::json to_json(const RayTextureSpec& s);
// The spec with one more stroke, same lineage. Throws SceneError beyond kMaxRayTextureStrokes.
std::shared_ptr<const RayTextureSpec> with_stroke(const RayTextureSpec& spec, const Stroke& s);

// A region of level-0 texels, [x0, x1) x [y0, y1); empty when x0 >= x1 or y0 >= y1.
struct TexelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
  void merge(const TexelRect& r);
};

class RayTexture {
 public:
  // Every texel at the defaults; `termination` is the scene's early-termination opacity.
  RayTexture(int width, int height, double termination);
  explicit RayTexture(const RayTextureImage& image);
  int width() const { return width_; }
  int height() const { return height_; }
  // Applies a stroke (direct, or on its level's blocks) and returns the texels it changed.
  TexelRect apply(const Stroke& s);
  // step, termination, blend at texel (x, y).
  std::array<float, 3> at(int x, int y) const;
  // Interleaved RGB floats, row 0 = v 0 (the top of a view-aligned image).
  const std::vector<float>& texels() const { return texels_; }
  // True when no texel differs from the defaults.
  bool is_identity() const;
  // The texture as a view of its image: what a PNG of it reads back as (rounded to 8 bits).
  RayTextureImage image() const { return {width_, height_, texels_}; }

 private:
  int width_, height_;
  float default_termination_;
  std::vector<float> texels_;
};

// The texture of a spec at the scene's termination: its image (or the defaults), then its
// strokes in order. Throws SceneError when the spec names a PNG that was never read.
RayTexture build_ray_texture(const RayTextureSpec& spec, double termination);

}  // namespace peakcast
