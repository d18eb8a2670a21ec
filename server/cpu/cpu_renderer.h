// The native CPU backend (docs/performance.md has the decision and its numbers): the
// GL ray caster's algorithm and scene contract on the host, for machines whose EGL offers only
// a software rasteriser. Threads take 16x16-pixel tiles; each ray is cpu/ray_kernel.cpp, its
// samples reconstructed a SIMD run at a time (cpu/sampler_simd.cpp); the volume is read where
// it already lies in host memory (CpuVolume).
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "cpu/cpu_volume.h"
#include "cpu/ray_kernel.h"
#include "render/frame_setup.h"
#include "render/ray_texture_cache.h"
#include "render/renderer.h"

namespace peakcast::cpu {

class CpuRenderer : public render::Renderer {
 public:
  // threads <= 0: every core.
  explicit CpuRenderer(int threads = 0);
  const char* backend() const override { return "cpu"; }
  std::string description() const override;
  std::unique_ptr<render::ResidentVolume> make_resident(std::shared_ptr<const Volume> volume,
                                                        VolumeMacrocells cells = {}) override;
  using Renderer::render;
  // `volume` must be a CpuVolume (std::invalid_argument otherwise). The GL path in the request
  // is ignored: both draw the same pixels.
  render::RenderResult render(const render::ResidentVolume& volume, const ResolvedScene& scene,
                              const render::RenderRequest& request, render::RenderStats* stats = nullptr) override;
  int sample_cap(const render::VariantKey&) const override;

  using Brick = render::Brick;
  Image render_brick(const render::ResidentVolume& volume, const ResolvedScene& scene, const Brick& brick,
                     render::RenderStats* stats = nullptr,
                     std::optional<render::PixelRect> rect = std::nullopt) override;

 protected:
  // The frame's inputs, from the caches (built on a miss).
  CpuFrame prepare(const CpuVolume& volume, const ResolvedScene& scene, render::RenderPath path,
                   const render::PixelRect& rect, const render::Brick* brick, render::RenderStats* stats);
  // for_each_row for a subclass's own per-pixel loop (peakcast-bench's bare sampling loop).
  void for_rows(const render::PixelRect& rect, const std::function<void(int, int, int)>& fn) const;
  // The SIMD fast paths, each held by a test to the shared code on the same rays (a test's
  // subclass turns them off): the 16-ray packet leaps of cast_rays (off: every ray alone,
  // cast_ray), and plain DVR's dense_run (off: every point through the shared visit).
  bool packets_ = true;
  bool dense_runs_ = true;

 private:
  // Calls fn(x0, x1, y) for the rows of every tile of `rect` (rect-relative pixels), tiles
  // spread over the threads.
  // Casts the rect's rays into res (rgb8 or float) and, when asked, their sample counts.
  void cast_rows(const CpuFrame& f, const render::PixelRect& rect, bool rgb8, bool read_samples,
                 const glm::vec3& background, render::RenderResult& res, std::vector<float>& samples) const;
  template <class PerRow>
  void for_each_row(const render::PixelRect& rect, const PerRow& fn) const;

  int threads_ = 1;
  struct TfTable {
    std::string key;
    std::vector<float> rgba;
    std::vector<uint64_t> alpha_any;  // tf_cell_bits
  };
  struct Tables {  // peak table + TF points, or the preintegration table
    std::string key;
    std::vector<float> peak_texels;
    int peak_bins = 0, peak_layers = 0;
    std::vector<glm::vec4> tf_points;
    std::vector<float> preint;
    int preint_size = 0;
    std::vector<uint64_t> peak_any, preint_any;  // table_bits: which lookups can find something
  };
  struct CellBytes {  // empty-space distances of one occupancy, or adaptive multipliers of one grid
    std::string key;
    std::vector<uint8_t> bytes;
    bool any_occupied = true;  // distances: some cell has distance 0 (something to sample)
  };
  const TfTable& tf_table(const ResolvedScene& s, const std::string& tf_sig, double lo, double hi);
  const Tables& tables(const ResolvedScene& s, const std::vector<Peak>& peaks, double lo, double hi);
  void cell_tables(CpuFrame& f, const CpuVolume& cv, const MacrocellGrid& cells, const render::FrameSetup& fs);
  static constexpr size_t kCacheEntries = 4;
  std::vector<TfTable> tf_tables_;
  std::vector<Tables> tables_;
  render::OccupancyCache occupancy_;
  std::vector<CellBytes> distances_, multipliers_;
  struct CellRanges {  // a grid's value ranges (projections)
    std::string key;
    std::vector<glm::vec2> ranges;
  };
  std::vector<CellRanges> ranges_;
  struct NoCopy {};
  render::RayTextureCache<NoCopy> ray_textures_;
};

}  // namespace peakcast::cpu
