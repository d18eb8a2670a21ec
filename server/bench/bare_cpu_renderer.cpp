// The CPU backend with the bare sampling loop (bare_sampling.h).
#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "bench/bare_kernel.h"
#include "bench/bare_sampling.h"
#include "cpu/cpu_renderer.h"
#include "render/ray_uniforms.h"
#include "render/variant.h"

namespace peakcast::bench {
namespace {

class BareCpuRenderer final : public render::Switchable<cpu::CpuRenderer, BareSampling> {
 public:
  Image render_bare(const render::ResidentVolume& v, const ResolvedScene& s, render::RenderPath path, const Image& full,
                    render::RenderStats* stats) override {
    const auto* cv = dynamic_cast<const cpu::CpuVolume*>(&v);
    if (!cv) throw std::invalid_argument("render_bare: not a CPU backend volume");
    const int w = s.scene.width, h = s.scene.height;
    if (full.width != w || full.height != h) throw std::invalid_argument("render_bare: image size differs");
    if (stats) *stats = render::RenderStats::for_scene(s);
    const render::PixelRect all{0, 0, w, h};
    cpu::CpuFrame f = prepare(*cv, s, path, all, nullptr, nullptr);
    f.key = render::choose_variant(s, 0, path);
    f.key.cpu = true;
    f.key.shading = false;
    f.v = render::shared_variant(f.key);
    Image img(w, h);
    const auto t0 = std::chrono::steady_clock::now();
    for_rows(all, [&](int x0, int x1, int y) {
      for (int x = x0; x < x1; ++x) {
        const size_t p = size_t(y) * size_t(w) + size_t(x);
        const int budget = int(std::max(0.f, full.samples[p]));
        const cpu::RayResult r = cast_ray_bare(f, float(x) + 0.5f, float(y) + 0.5f, budget);
        img.rgba[p * 4 + 3] = r.acc.a;
        img.samples[p] = r.samples;
      }
    });
    if (stats) {
      stats->render_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      stats->variant = f.key.name() + "+bare";
      stats->has_samples = true;
      for (float n : img.samples) {  // as the full render counts them (every ray's budget)
        stats->samples_total += n;
        stats->samples_max = std::max<double>(stats->samples_max, n);
        stats->rays_hit += n > 0 ? 1 : 0;
      }
      stats->samples_mean = stats->rays_hit ? stats->samples_total / double(stats->rays_hit) : 0.0;
    }
    return img;
  }
};

}  // namespace

std::unique_ptr<render::Renderer> make_bare_cpu_renderer(BareSampling*& hooks) {
  auto r = std::make_unique<BareCpuRenderer>();
  hooks = r.get();
  return r;
}

}  // namespace peakcast::bench
