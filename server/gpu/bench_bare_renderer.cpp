// The GL ray caster with the bare sampling loop (bench/bare_sampling.h): built into peakcast-bench
// only, never into the product; here because it makes GL calls. Its programs are its own
// (shaders/bench_raycast_bare.frag and .comp: the ray caster's entry points with the loop of
// shaders/bench_bare_sampling.glsl), built by the product's shader cache under their own names.
#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bare_sampling.h"
#include "gpu/gl_renderer.h"
#include "gpu/gl_volume.h"
#include "render/shader_interface.h"
#include "render/variant.h"

namespace peakcast::bench {
namespace {

// The budget texture's unit: one the product's layout (render/shader_interface.h) leaves free.
constexpr unsigned kUnitBudget = 3;
static_assert(kUnitBudget != render::kUnitVolume && kUnitBudget != render::kUnitTf &&
              kUnitBudget != render::kUnitPeakTable && kUnitBudget != render::kUnitPreint &&
              kUnitBudget != render::kUnitRayTexture);

class BareGlRenderer final : public render::Switchable<gpu::GlRenderer, BareSampling> {
 public:
  explicit BareGlRenderer(gpu::ShaderCache& shaders) : Switchable(shaders), shaders_(shaders) {}
  // The bare loop's program while render_bare draws, else the product's.
  const gpu::Program& program(const render::VariantKey& key) override {
    if (!bare_) return Switchable::program(key);
    auto defines = key.defines();
    defines.push_back("UNIT_BUDGET " + std::to_string(kUnitBudget));
    if (key.path == render::RenderPath::Compute)
      return shaders_.get("bare:" + key.name(), {"bench_raycast_bare.comp"}, defines);
    return shaders_.get("bare:" + key.name(), {"fullscreen.vert", "bench_raycast_bare.frag"}, defines);
  }
  Image render_bare(const render::ResidentVolume& v, const ResolvedScene& s, render::RenderPath path, const Image& full,
                    render::RenderStats* stats) override {
    const auto* gv = dynamic_cast<const gpu::GlVolume*>(&v);
    if (!gv) throw std::invalid_argument("render_bare: not a GL backend volume");
    const int w = s.scene.width, h = s.scene.height;
    if (full.width != w || full.height != h) throw std::invalid_argument("render_bare: image size differs");
    std::vector<float> budget(full.samples.size());  // rows top-down, like the render targets
    for (size_t p = 0; p < budget.size(); ++p) budget[p] = std::max(0.f, full.samples[p]);
    budget_ = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(budget_.id(), 1, GL_R32F, w, h);
    glTextureSubImage2D(budget_.id(), 0, 0, 0, w, h, GL_RED, GL_FLOAT, budget.data());
    glTextureParameteri(budget_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(budget_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTextureUnit(kUnitBudget, budget_.id());
    render::VariantKey key = render::choose_variant(s, 0, path);
    key.shading = false;
    if (stats) *stats = render::RenderStats::for_scene(s);
    bare_ = true;
    struct Reset {
      bool& b;
      ~Reset() { b = false; }
    } reset{bare_};
    Image img = std::move(draw(*gv, s, key, render::PixelRect{0, 0, w, h}, true, stats).image);
    if (stats) stats->variant += "+bare";
    return img;
  }

 private:
  gpu::ShaderCache& shaders_;
  gpu::Texture budget_;  // the per-pixel sample counts of `full`
  bool bare_ = false;    // render_bare is drawing
};

}  // namespace

std::unique_ptr<render::Renderer> make_bare_gl_renderer(gpu::ShaderCache& shaders, BareSampling*& hooks) {
  auto r = std::make_unique<BareGlRenderer>(shaders);
  hooks = r.get();
  return r;
}

}  // namespace peakcast::bench
