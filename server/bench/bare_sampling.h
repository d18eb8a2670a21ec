// The ceiling peakcast-bench measures the ray caster against: the bare sampling loop, the same
// rays and the same number of samples per ray as a full render, reconstruction only (no TF, no
// compositing). The benchmark's renderers are the product's with this loop and the renderer's
// switches added (make_bench_renderer, bench_scenes.h); the product's renderers carry neither.
#pragma once

#include <memory>

#include "core/image.h"
#include "core/scene.h"
#include "render/renderer.h"
#include "render/renderer_switches.h"

namespace peakcast::gpu {
class ShaderCache;
}

namespace peakcast::bench {

class BareSampling : public render::RendererSwitches {
 public:
  // The rays of `full` (an image this renderer made of the same scene just before: its tables
  // are bound) with its per-pixel sample counts, reconstruction only. Its render time in stats.
  virtual Image render_bare(const render::ResidentVolume& volume, const ResolvedScene& scene, render::RenderPath path,
                            const Image& full, render::RenderStats* stats = nullptr) = 0;
};

// The CPU backend with the loop; `hooks` is set to the same object.
std::unique_ptr<render::Renderer> make_bare_cpu_renderer(BareSampling*& hooks);
// The GL ray caster on `shaders`' device with the loop (GL builds: server/gpu/bench_bare_renderer.cpp).
std::unique_ptr<render::Renderer> make_bare_gl_renderer(gpu::ShaderCache& shaders, BareSampling*& hooks);

}  // namespace peakcast::bench
