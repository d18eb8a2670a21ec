// The GL backend's ray caster (docs/architecture.md, docs/scenes.md): one fullscreen draw
// (fragment path) or one dispatch (compute path) per frame or tile, into targets that hold rows
// top-down (no flip on read): float (an Image) or 8-bit RGB quantised on the GPU (render/frame.h).
#pragma once

#include <chrono>
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
#include "render/frame_setup.h"
#include "gpu/gl_volume.h"
#include "render/ray_texture_cache.h"
#include "render/render_stats.h"
#include "render/renderer.h"
#include "render/variant.h"

namespace peakcast::gpu {

// Sizes of the per-TF tables bound for a frame.
struct RayTables {
  int peak_bins = 0, peak_layers = 0, max_peaks = 0, secant_iterations = 0;
  int preint_size = 0, tf_points = 0;
  size_t peak_count = 0;
};

class GlRenderer : public render::Renderer {
 public:
  explicit GlRenderer(gpu::ShaderCache& shaders);
  const char* backend() const override { return "gl"; }
  std::string description() const override;
  // A GlVolume: the texture upload.
  std::unique_ptr<render::ResidentVolume> make_resident(std::shared_ptr<const Volume> volume,
                                                        VolumeMacrocells cells = {}) override;
  using render::Renderer::render;
  // `volume` must be a GlVolume (std::invalid_argument otherwise).
  render::RenderResult render(const render::ResidentVolume& volume, const ResolvedScene& scene,
                              const render::RenderRequest& request, render::RenderStats* stats = nullptr) override;
  // The fragment path with BRICK: ownership, look-behind and look-ahead as the CPU backend's.
  Image render_brick(const render::ResidentVolume& volume, const ResolvedScene& scene, const render::Brick& brick,
                     render::RenderStats* stats = nullptr,
                     std::optional<render::PixelRect> rect = std::nullopt) override;
  int sample_cap(const render::VariantKey& key) const override;
  // The linked program of a variant (also for the layout test); a subclass may draw its own
  // (peakcast-bench's bare sampling loop).
  virtual const gpu::Program& program(const render::VariantKey& key);

 protected:
  // One synchronous draw of `key` over `rect` (a subclass's own variant: peakcast-bench's bare
  // sampling loop), read back; the per-TF tables must have been bound by a render of the scene.
  render::RenderResult draw(const GlVolume& volume, const ResolvedScene& scene, const render::VariantKey& key,
                            const render::PixelRect& rect, bool read_samples, render::RenderStats* stats,
                            const render::Brick* brick = nullptr);

 private:
  // Render targets of one size and format. A few are kept: a still's tiles interleave with
  // stream frames of another size, and reallocating every draw would cost more than the tile.
  struct Targets {
    int w = 0, h = 0;
    render::RenderOutput output = render::RenderOutput::Float;
    gpu::Texture color, samples;
    gpu::Framebuffer fbo;
  };
  Targets& targets(int w, int h, render::RenderOutput output);
  // Tables, occupancy and the variant for a scene (cached on the TF).
  render::VariantKey prepare(const GlVolume& volume, const ResolvedScene& scene, render::RenderPath path,
                             render::RenderStats* stats);
  // Builds and binds the peak table + TF points or the preintegration table the scene needs.
  void upload_tables(const GlVolume& volume, const ResolvedScene& scene, const std::vector<Peak>& peaks);
  void bind_tf_table(const GlVolume& volume, const ResolvedScene& scene, const std::string& tf_sig);
  void bind_multipliers(const GlVolume& volume, const MacrocellGrid& cells);
  void bind_cell_ranges(const GlVolume& volume, const MacrocellGrid& cells);
  // A draw in parts, shared by draw() and the asynchronous frames: the program (its wait in
  // stats->compile_ms), uniforms and targets; then the draw or dispatch between a timer
  // query's begin and end; then the query's result (waits for it).
  Targets& setup_draw(const GlVolume& volume, const ResolvedScene& scene, const render::VariantKey& key,
                      const render::PixelRect& rect, const render::Brick* brick, render::RenderStats* stats);
  void dispatch(const render::VariantKey& key, Targets& targets, bool read_samples, const gpu::GpuTimer& timer);

  gpu::ShaderCache& shaders_;
  gpu::Buffer ubo_;
  gpu::Buffer front_opacity_;  // render_brick with a ray texture: Brick::front_opacity
  gpu::VertexArray vao_;
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
  struct DistanceEntry {  // the empty-space distance per cell of one occupancy (its key)
    std::string key;
    gpu::Buffer buffer;
  };
  static constexpr size_t kCacheEntries = 4;
  std::vector<TfTable> tf_tables_;
  std::vector<Tables> tables_cache_;
  render::OccupancyCache occupancy_cache_;
  std::vector<DistanceEntry> distance_cache_;
  struct StrideEntry {  // adaptive multipliers, or the value ranges, of one volume's grid
    std::string key;
    gpu::Buffer buffer;
  };
  std::vector<StrideEntry> stride_cache_, range_cache_;
  // Ray textures on the host (strokes read them: add, multiply), each with its texture.
  using RayTextureEntry = render::RayTextureCache<gpu::Texture>::Entry;
  render::RayTextureCache<gpu::Texture> ray_textures_;
  // Binds the scene's ray texture: a new lineage is uploaded whole; new strokes of a held one
  // upload only the texels they touched (Raspe §3.2).
  void bind_ray_texture(const ResolvedScene& scene, render::RenderStats* stats);
  RayTables tables_;  // what the current frame's tables hold (for the uniforms and stats)
  bool llvmpipe_ = false;
  render::VariantKey last_key_;   // the last draw's variant (prefetch_variants starts from it)
  std::vector<Targets> targets_;  // most recently used first
  gpu::GpuTimer timer_;           // the synchronous draws' timer

  // Asynchronous frames (gl_renderer_async.cpp): a ring of pixel-buffer objects, each with the
  // fence after its read-back and its draw's timer query.
  struct InFlight {
    gpu::Buffer pbo;
    size_t bytes = 0;  // the buffer's size
    gpu::GpuTimer timer;
    gpu::Fence fence;
    int w = 0, h = 0, cap = 0;
    bool samples = false;  // per-pixel sample counts follow the RGB bytes
    render::RenderStats stats;
    std::chrono::steady_clock::time_point issued;
  };
  std::vector<InFlight> ring_;  // kFramesInFlight slots
  size_t ring_head_ = 0, ring_count_ = 0;

 public:
  void submit(const render::ResidentVolume& volume, const ResolvedScene& scene,
              const render::RenderRequest& request) override;
  render::RenderResult collect(render::RenderStats* stats = nullptr) override;
  size_t in_flight() const override { return ring_count_; }
  bool asynchronous() const override { return !llvmpipe_; }
  void prefetch_variants() override;
};

// Adds per-pixel sample counts (-1: the ray missed the box) to the stats.
void count_samples(const std::vector<float>& samples, int cap, render::RenderStats& stats);

using peakcast::kMaxSamplesPerRay;
constexpr int kLlvmpipeLoopBudget = 60000;  // of llvmpipe's 65535 loop iterations per invocation

}  // namespace peakcast::gpu
