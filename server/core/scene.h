// A scene: volume, camera, image size, TF, background and render settings (docs/scenes.md,
// proto/scene.schema.json). Parsing refuses unknown keys, wrong types, NaN/Inf, unsorted TFs,
// zero or oversized images and degenerate cameras, naming the key.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/clip.h"
#include "core/ray_texture.h"
#include "core/scene_error.h"
#include "core/transfer_function.h"
#include "core/volume.h"

namespace peakcast {

// Limits at the edge, with units.
constexpr int kMaxImageSide = 8192;                 // pixels per side
constexpr int64_t kMaxImagePixels = 4096ll * 4096;  // pixels per image
constexpr size_t kMaxTfPoints = 1024;               // TF control points
constexpr double kMinStepFraction = 1e-3;           // step >= this x smallest spacing

enum class Classification { Post, Preint, Peaks, Mip, Minip, Average };
// The intensity projections (mip, minip, average): the TF colours one value per ray.
bool is_projection(Classification c);
enum class PeakMode { DvrPlusPeaks, Xor, PeaksOnly, DvrOnly };
enum class Sampling { Uniform, Differential };
enum class Filter { Trilinear, Tricubic };

struct RenderSettings {
  Classification classification = Classification::Post;
  PeakMode peak_mode = PeakMode::DvrPlusPeaks;
  int max_peaks = 4;
  int peak_table_bins = 128;            // 64..1024
  int secant_iterations = 3;            // root-solving steps per peak (Knoll §4.2)
  int preint_table_size = 256;          // 16..1024
  std::string preint_method = "exact";  // exact (composited pieces, O(N^2)) | integral (Engel's approximation)
  Sampling sampling = Sampling::Uniform;
  double step = 0.0;  // world units; 0: the smallest spacing
  double s_k = 4.0;
  Filter filter = Filter::Trilinear;
  int virtual_samples = 0;
  bool shading = false;
  double early_termination = 1.0 - 1.0 / 255.0;
  bool space_skipping = true;
  bool adaptive = false;
  ClipSettings clip;  // none by default
  // Parsed once, shared and immutable (a painted stroke makes a new spec); null when absent.
  std::shared_ptr<const RayTextureSpec> ray_texture;
};

struct Scene {
  std::string volume;
  std::optional<Camera> camera;  // default: default_camera() of the volume box
  int width = 512, height = 512;
  std::optional<TransferFunction> tf;  // default: derived from the histogram (auto_tf.h)
  double opacity_unit = 0.0;
  glm::dvec3 background{0, 0, 0};
  RenderSettings render;
  // The unit of the volume's spacing, an SI symbol (core/length_unit.h), for a file that names
  // none or names it wrong; "": the volume's own. Shown with lengths; nothing drawn changes.
  std::string units;
  // A time series' time point (docs/scenes.md, "Time"): 0 .. the volume's `times` - 1.
  int64_t time = 0;
  std::string to_string() const;
};

Scene parse_scene(const nlohmann::json& j);  // throws SceneError
Scene parse_scene_text(const std::string& text);
nlohmann::json scene_to_json(const Scene& s);

// A scene with every default filled in for a given volume.
struct ResolvedScene {
  Scene scene;
  Camera camera;
  TransferFunction tf;  // with opacity_unit set
  double step = 1.0;
  double min_spacing = 1.0;  // the volume's smallest voxel spacing
  glm::dvec3 box_min, box_max;
  // render.ray_texture (its PNG read); null without one. Its texels are built where they are
  // read (build_ray_texture at the scene's early termination): the GL ray caster keeps them
  // per lineage and applies only new strokes, the CPU reference builds them once per image.
  std::shared_ptr<const RayTextureSpec> ray_texture;
  // The scene came without a TF, and `tf` was derived from the volume's histogram (auto_tf.h).
  bool tf_derived = false;
  // What the scene asks for that it will not get, in words for the user (the stats carry them):
  // peak finding with a TF that has no opacity peak inside the data's range.
  std::vector<std::string> warnings;
};
// Refuses (SceneError naming `time`) a scene whose time point is not the one `v` holds.
ResolvedScene resolve_scene(const Scene& s, const Volume& v);
// The refusal of a time point past a series of `times` points ("" when it is one of them).
std::string time_refusal(int64_t time, int64_t times);
// What resolving needs of a volume: its box, value range and histogram (for a derived TF; none:
// a ramp over the range). Distributed rendering resolves against the whole volume's, which no
// rank holds.
struct VolumeBox {
  std::array<int64_t, 3> dims{0, 0, 0};
  glm::dvec3 spacing{1.0}, origin{0.0};
  double min_value = 0.0, max_value = 0.0;
  std::vector<uint64_t> histogram;         // Volume::kHistogramBins bins over the range, or empty
  std::vector<uint64_t> border_histogram;  // Volume::border_histogram: the faces' voxels, or empty
  // A coarser pyramid level: level 0's spacing (Volume::full_spacing), which the default opacity
  // unit and the automatic TF follow; {0, 0, 0}: `spacing`.
  glm::dvec3 full_spacing{0.0};
};
ResolvedScene resolve_scene(const Scene& s, const VolumeBox& v);

const char* to_string(Classification c);
const char* to_string(PeakMode m);
const char* to_string(Sampling s);
const char* to_string(Filter f);

}  // namespace peakcast
