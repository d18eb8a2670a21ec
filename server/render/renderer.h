// The ray caster's interface, whichever backend draws: the GL ray caster (gpu/gl_renderer.h,
// shaders/) or the native CPU one (cpu/cpu_renderer.h). Both take the same scene contract
// (docs/scenes.md), choose the same variant and produce the same outputs; render/backend.h picks one.
#pragma once

#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "core/image.h"
#include "core/scene.h"
#include "render/brick.h"
#include "render/frame_setup.h"
#include "render/frame.h"
#include "render/render_stats.h"
#include "render/resident_volume.h"
#include "render/variant.h"

namespace peakcast::render {

class Renderer {
 public:
  virtual ~Renderer() = default;
  virtual const char* backend() const = 0;  // "gl" or "cpu"
  // A human-readable description (GL renderer string, or the CPU's SIMD target and threads).
  virtual std::string description() const = 0;

  // This backend's copy of a volume (the texture upload, or the CPU's view of the voxels).
  virtual std::unique_ptr<ResidentVolume> make_resident(std::shared_ptr<const Volume> volume,
                                                        VolumeMacrocells cells = {}) = 0;

  // Float or 8-bit output, whole image or a tile (checked: std::invalid_argument naming the
  // limit). Tables and occupancy are cached on the TF, so the tiles of one still rebuild
  // nothing after the first. `volume` must come from this backend's make_resident.
  virtual RenderResult render(const ResidentVolume& volume, const ResolvedScene& scene, const RenderRequest& request,
                              RenderStats* stats = nullptr) = 0;
  // The whole image as floats (tests, CLI, reference comparisons).
  Image render(const ResidentVolume& volume, const ResolvedScene& scene, RenderPath path = RenderPath::Fragment,
               RenderStats* stats = nullptr) {
    RenderRequest req;
    req.path = path;
    return std::move(render(volume, scene, req, stats).image);
  }
  // Distributed rendering: the brick's layer of the frame (render/brick.h), whole image or a
  // tile of it; `volume` holds the brick's region of the whole volume. Float RGBA,
  // premultiplied, no background; samples -1 where the ray owns no lattice point here.
  virtual Image render_brick(const ResidentVolume& volume, const ResolvedScene& scene, const Brick& brick,
                             RenderStats* stats = nullptr, std::optional<PixelRect> rect = std::nullopt) = 0;
  // The most samples a ray of this variant takes (kMaxSamplesPerRay, or less where a driver
  // bounds a shader's loops: llvmpipe); rays that reach it are counted in the stats.
  virtual int sample_cap(const VariantKey& key) const = 0;

  // The stream's frames, drawn and read back asynchronously. submit() draws the whole image as
  // 8-bit RGB (`request.output` must be Rgb8, no tile) and starts its read-back; collect()
  // returns the oldest frame submitted and not yet collected, waiting for it, with its stats.
  // The render thread draws frame N + 1 between the two calls for frame N, so the read-back
  // and encode of one frame overlap the next frame's draw. At most kFramesInFlight frames are
  // submitted and not collected (std::logic_error beyond; collect with none: the same). This
  // default draws and reads back inside submit(): the CPU backend has nothing to overlap.
  static constexpr size_t kFramesInFlight = 2;
  virtual void submit(const ResidentVolume& volume, const ResolvedScene& scene, const RenderRequest& request);
  virtual RenderResult collect(RenderStats* stats = nullptr);
  virtual size_t in_flight() const { return done_.size(); }
  // Whether drawing the next frame before collecting this one overlaps work (a GPU's draw with
  // the host's read-back and encode). False for the default, where it would only delay this
  // frame by the next one's whole render, and on llvmpipe, which draws on the same cores.
  virtual bool asynchronous() const { return false; }
  // Prepares, off the render thread, what the next frames may need that the last one did not
  // (GL: the shader variants of the other classifications, shading toggled, still output), so a
  // session that switches does not wait for a compile. Nothing to prepare by default.
  virtual void prefetch_variants() {}

 protected:
  // How frames are set up (the product's defaults; subclasses in tests and peakcast-bench change
  // them: render/renderer_switches.h), and the per-TF tables and occupancy grids built so far.
  SetupOptions setup_options_;
  size_t table_builds_ = 0;

  static void check_submit(const RenderRequest& request, size_t in_flight);

 private:
  struct Done {
    RenderResult result;
    RenderStats stats;
  };
  std::deque<Done> done_;  // the default submit's frames, oldest first
};

}  // namespace peakcast::render
