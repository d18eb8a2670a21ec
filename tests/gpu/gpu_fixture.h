// One renderer per test process, and image-test helpers: failures write actual, expected and
// diff PNGs under build/test-artifacts/.
//
// The renderer is the GL ray caster (an EGL context and shader cache), or the native CPU
// backend when PEAKCAST_TEST_BACKEND=cpu: CTest runs every binary of these folders once per
// backend (tests/gpu/CMakeLists.txt), so each method is held to the same bounds on both.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "core/generators.h"
#include "core/image.h"
#include "core/scene.h"
#include "gpu/egl_context.h"
#include "gpu/shader_cache.h"
#include "reference/metrics.h"
#include "gpu/gl_volume.h"
#include "gpu/gl_renderer.h"
#include "cpu/cpu_renderer.h"
#include "render/renderer.h"
#include "render/renderer_switches.h"

namespace peakcast::test {

// The CPU backend with its SIMD fast paths switchable: each is held to the shared code on the
// same rays.
class TestCpuRenderer final : public render::Switchable<cpu::CpuRenderer> {
 public:
  // Off: every ray alone (cast_ray), without the packet leaps of cast_rays.
  void set_ray_packets(bool on) { packets_ = on; }
  // Off: plain DVR walks every point through the shared visit, without the dense_run fast path.
  void set_dense_runs(bool on) { dense_runs_ = on; }
};

struct Gpu {
  std::unique_ptr<gpu::EglContext> context;  // GL backend only
  std::unique_ptr<gpu::ShaderCache> shaders;
  std::unique_ptr<render::Renderer> caster;      // the backend under test (a test subclass of the product's)
  gpu::GlRenderer* gl = nullptr;                 // the same renderer when it is the GL one
  TestCpuRenderer* cpu = nullptr;                // the same renderer when it is the CPU one
  render::RendererSwitches* switches = nullptr;  // the same renderer's switches
};
Gpu& gpu();          // created on first use
bool cpu_backend();  // PEAKCAST_TEST_BACKEND=cpu
// Skips the current test under a backend it does not apply to (GL shader programs, llvmpipe's
// loop limit).
#define PEAKCAST_GL_ONLY()                                                  \
  do {                                                                      \
    if (::peakcast::test::cpu_backend()) GTEST_SKIP() << "GL backend only"; \
  } while (0)

// A volume made ready for the backend under test (a GlVolume or a CpuVolume).
class TestVolume {
 public:
  explicit TestVolume(std::shared_ptr<const Volume> v, VolumeMacrocells cells = {});
  operator const render::ResidentVolume&() const { return *r_; }
  const render::ResidentVolume& get() const { return *r_; }
  const MacrocellGrid& macrocells(Filter f) const { return r_->macrocells(f); }
  double tf_lo() const { return r_->tf_lo(); }
  double tf_hi() const { return r_->tf_hi(); }
  double macrocell_ms() const { return r_->macrocell_ms(); }

 private:
  std::unique_ptr<render::ResidentVolume> r_;
};

// A scene resolved for `v`, with optional JSON overrides merged over the defaults.
ResolvedScene make_scene(const Volume& v, const nlohmann::json& overrides = {});
std::shared_ptr<Volume> make_volume(GeneratorKind kind, Dims dims, SourceType type, glm::dvec3 spacing = {1, 1, 1});

Image render_gpu(const render::ResidentVolume& gv, const ResolvedScene& s, render::RenderPath path,
                 render::RenderStats* stats = nullptr);

// Writes actual/expected/diff PNGs named after the current test.
void save_artifacts(const Image& actual, const Image& expected, const std::string& tag);
bool all_finite(const Image& img);

}  // namespace peakcast::test
