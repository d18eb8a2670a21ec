// One EGL context and shader cache per test process, and image-test helpers: failures write
// actual, expected and diff PNGs under build/test-artifacts/.
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
#include "render/gpu_volume.h"
#include "render/raycaster.h"

namespace peakcast::test {

struct Gpu {
  std::unique_ptr<gpu::EglContext> context;
  std::unique_ptr<gpu::ShaderCache> shaders;
  std::unique_ptr<render::Raycaster> caster;
};
Gpu& gpu();  // created on first use

// A scene resolved for `v`, with optional JSON overrides merged over the defaults.
ResolvedScene make_scene(const Volume& v, const nlohmann::json& overrides = {});
std::shared_ptr<Volume> make_volume(GeneratorKind kind, Dims dims, SourceType type,
                                    glm::dvec3 spacing = {1, 1, 1});

Image render_gpu(const render::GpuVolume& gv, const ResolvedScene& s, render::GpuPath path,
                 render::RenderStats* stats = nullptr);

// Writes actual/expected/diff PNGs named after the current test.
void save_artifacts(const Image& actual, const Image& expected, const std::string& tag);
bool all_finite(const Image& img);

}  // namespace peakcast::test
