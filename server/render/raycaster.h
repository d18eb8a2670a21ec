// The GL ray caster (DESIGN §3, §4a): one fullscreen draw (fragment path) or one dispatch
// (compute path) per frame or tile, into targets that hold rows top-down (no flip on read):
// float (an Image) or 8-bit RGB quantised on the GPU (render/frame.h).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/occupancy.h"
#include "core/peaks.h"
#include "core/sampling.h"
#include "core/ray_texture.h"
#include "core/scene.h"
#include "gpu/gl_objects.h"
#include "gpu/shader_cache.h"
#include "render/frame.h"
#include "render/gpu_volume.h"
#include "render/render_stats.h"
#include "render/variant.h"

namespace peakcast::render {

// Sizes of the per-TF tables bound for a frame.
struct RayTables {
  int peak_bins = 0, peak_layers = 0, max_peaks = 0, secant_iterations = 0;
  int preint_size = 0, tf_points = 0;
  size_t peak_count = 0;
};

class Raycaster {
 public:
  explicit Raycaster(gpu::ShaderCache& shaders);
  // The whole image as floats (tests, CLI, reference comparisons).
  Image render(const GpuVolume& volume, const ResolvedScene& scene, GpuPath path, RenderStats* stats = nullptr);
  // Float or 8-bit output, whole image or a tile (checked: std::invalid_argument naming the
  // limit). Tables and occupancy are cached on the TF, so the tiles of one still rebuild
  // nothing after the first.
  RenderResult render(const GpuVolume& volume, const ResolvedScene& scene, const RenderRequest& request,
                      RenderStats* stats = nullptr);
  // Benchmark baseline: the rays of `full` (an image this caster rendered of the same scene)
  // with its per-pixel sample counts, reconstruction only.
  Image render_bare(const GpuVolume& volume, const ResolvedScene& scene, GpuPath path, const Image& full,
                    RenderStats* stats = nullptr);
  // TF tables, peak/preintegration tables and occupancy grids built so far (for tests: tiles
  // interleaved with another session's frames must not rebuild them).
  size_t table_builds() const { return table_builds_; }
  // How far the cells' value ranges are widened for virtual samples, as a fraction of each
  // range: Lee's 1/8 (kCatmullRomOvershoot). Tests set 0 to show the skipped-cell streaks it
  // prevents (Lee Fig. 14).
  void set_virtual_sample_widening(double fraction) { vs_widening_ = fraction; }
  // Off: the traversal steps through every empty macrocell one at a time instead of leaping
  // by the empty-space distance (tests show the leaps skip exactly what the steps skip).
  void set_empty_space_leaps(bool on) { leaps_ = on; }
  // Changes the variant chosen for every later frame (nullptr: none): how tests and the quality
  // bench put back code the scene's variant leaves out, to show the omission changes no pixel
  // and to time what it saves. Only features whose tables the frame builds anyway may be forced
  // on (peaks, space skipping, the differential lattice).
  void force_variant(std::function<void(VariantKey&)> change) { force_variant_ = std::move(change); }
  // The most samples a ray of this variant takes (kMaxSamplesPerRay, or less where the driver
  // bounds a shader's loops: llvmpipe); rays that reach it are counted in the stats.
  int sample_cap(const VariantKey& key) const;
  // For the layout test: the linked program of a variant.
  const gpu::Program& program(const VariantKey& key);

 private:
  // Render targets of one size and format. A few are kept: a still's tiles interleave with
  // stream frames of another size, and reallocating every draw would cost more than the tile.
  struct Targets {
    int w = 0, h = 0;
    RenderOutput output = RenderOutput::Float;
    gpu::Texture color, samples;
    gpu::Framebuffer fbo;
  };
  Targets& targets(int w, int h, RenderOutput output);
  // Tables, occupancy and the variant for a scene (cached on the TF).
  VariantKey prepare(const GpuVolume& volume, const ResolvedScene& scene, GpuPath path, RenderStats* stats);
  // Builds and binds the peak table + TF points or the preintegration table the scene needs.
  void upload_tables(const GpuVolume& volume, const ResolvedScene& scene, const std::vector<Peak>& peaks);
  void bind_tf_table(const GpuVolume& volume, const ResolvedScene& scene, const std::string& tf_sig);
  void bind_multipliers(const GpuVolume& volume, const MacrocellGrid& cells);
  RenderResult draw(const GpuVolume& volume, const ResolvedScene& scene, const VariantKey& key, const PixelRect& rect,
                    bool read_samples, RenderStats* stats);

  gpu::ShaderCache& shaders_;
  gpu::Buffer ubo_;
  gpu::VertexArray vao_;
  gpu::Texture budget_texture_;
  // Per-TF state in small caches, most recent first: sessions with different TFs (and a still's
  // tiles between their frames) take turns without rebuilding tables at every draw.
  struct TfTable {  // the 1D TF table over the value range
    std::string key;
    gpu::Texture texture;
  };
  struct Tables {  // peak table + TF points, or the preintegration table
    std::string key;
    RayTables sizes;
    gpu::Texture peak_table, preint_table;
    gpu::Buffer tf_points;
  };
  struct OccupancyEntry {  // macrocell classification of one volume's grid under one TF
    std::string key;
    Occupancy occupancy;
    gpu::Buffer buffer;  // the empty-space distance per cell
  };
  static constexpr size_t kCacheEntries = 4;
  std::vector<TfTable> tf_tables_;
  std::vector<Tables> tables_cache_;
  std::vector<OccupancyEntry> occupancy_cache_;
  struct StrideEntry {  // adaptive multipliers of one volume's grid
    std::string key;
    gpu::Buffer buffer;
  };
  std::vector<StrideEntry> stride_cache_;
  // A ray texture of one lineage at one termination: the texels of its first `strokes`
  // strokes, on the host (strokes read them: add, multiply) and in the texture.
  struct RayTextureEntry {
    std::string key;  // lineage, termination
    size_t strokes = 0;
    RayTexture texels;
    gpu::Texture texture;
  };
  static constexpr size_t kRayTextureEntries = 8;  // sessions painting at once, before rebuilds
  static constexpr size_t kRayTextureCacheBytes = size_t(192) << 20;  // host texels held (as much again on the GPU)
  std::vector<RayTextureEntry> ray_texture_cache_;
  // Binds the scene's ray texture: a new lineage is built and uploaded whole; new strokes of
  // a held one are applied and only the texels they touched are uploaded (Raspe §3.2).
  void bind_ray_texture(const ResolvedScene& scene, RenderStats* stats);
  RayTables tables_;  // what the current frame's tables hold (for the uniforms and stats)
  size_t table_builds_ = 0;
  bool leaps_ = true;
  double vs_widening_ = kCatmullRomOvershoot;
  std::function<void(VariantKey&)> force_variant_;
  bool llvmpipe_ = false;
  std::vector<Targets> targets_;  // most recently used first
};

using peakcast::kMaxSamplesPerRay;
constexpr int kLlvmpipeLoopBudget = 60000;  // of llvmpipe's 65535 loop iterations per invocation

}  // namespace peakcast::render
