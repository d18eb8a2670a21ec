// The GL ray caster (DESIGN §3, §4a): one fullscreen draw (fragment path) or one dispatch
// (compute path) per frame, into float targets read back as an Image (row 0 at the top).
#pragma once

#include <string>

#include "core/image.h"
#include "core/occupancy.h"
#include "core/peaks.h"
#include "core/scene.h"
#include "gpu/gl_objects.h"
#include "gpu/shader_cache.h"
#include "render/gpu_volume.h"
#include "render/variant.h"

namespace peakcast::render {

// Sizes of the per-TF tables bound for a frame.
struct RayTables {
  int peak_bins = 0, peak_layers = 0, max_peaks = 0, secant_iterations = 0;
  int preint_size = 0, tf_points = 0;
  size_t peak_count = 0;
};

struct RenderStats {
  double render_ms = 0.0;      // GPU work, draw to glFinish
  double readback_ms = 0.0;
  double samples_mean = 0.0;   // per ray that hits the box (skipped rays count with 0)
  double samples_max = 0.0;
  double samples_total = 0.0;
  int64_t rays_hit = 0;
  int64_t empty_cells = 0;
  size_t peaks = 0;
  double table_ms = 0.0;  // peak table / preintegration table / occupancy rebuilt for this frame
  std::string variant;
  std::string to_string() const;
};

class Raycaster {
 public:
  explicit Raycaster(gpu::ShaderCache& shaders);
  Image render(const GpuVolume& volume, const ResolvedScene& scene, GpuPath path, RenderStats* stats = nullptr);
  // Benchmark baseline: the rays of `full` (an image this caster rendered of the same scene)
  // with its per-pixel sample counts, reconstruction only.
  Image render_bare(const GpuVolume& volume, const ResolvedScene& scene, GpuPath path, const Image& full,
                    RenderStats* stats = nullptr);
  // For the layout test: the linked program of a variant.
  const gpu::Program& program(const VariantKey& key);

 private:
  void ensure_targets(int w, int h);
  // Builds and binds the peak table + TF points or the preintegration table the scene needs.
  void upload_tables(const GpuVolume& volume, const ResolvedScene& scene, const std::vector<Peak>& peaks);
  Image draw(const GpuVolume& volume, const ResolvedScene& scene, const VariantKey& key, RenderStats* stats);

  gpu::ShaderCache& shaders_;
  gpu::Buffer ubo_;
  gpu::VertexArray vao_;
  gpu::Texture tf_texture_, occupancy_texture_, budget_texture_, color_, samples_;
  gpu::Texture peak_table_, preint_table_;
  gpu::Buffer tf_points_;
  RayTables tables_;  // what the current frame's tables hold (for the uniforms and stats)
  std::string tf_table_key_;  // the TF (and value range) the 1D table holds
  std::string tables_key_;    // the inputs tables_ was built from
  Occupancy occupancy_;      // macrocell classification for occupancy_key_
  std::string occupancy_key_;
  gpu::Framebuffer fbo_;
  int target_w_ = 0, target_h_ = 0;
};

// Maximum samples per ray the shader will take (guards runaway loops).
constexpr int kMaxSamplesPerRay = 1 << 20;

}  // namespace peakcast::render
