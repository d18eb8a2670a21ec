// The volume and scene several benchmarks share (bench raycast's): blobs 256^3 (or any volume
// file, or a generator kind), four TF points over the range, a three-quarter view.
#pragma once

#include <memory>
#include <string>

#include "core/scene.h"
#include "core/volume.h"
#include "gpu/egl_context.h"
#include "gpu/shader_cache.h"
#include "render/raycaster.h"

namespace peakcast::app {

// A file, or a generator kind made in memory at a modest size (ML 128^3, the others 256^3).
std::shared_ptr<Volume> bench_volume(const std::string& what);
ResolvedScene bench_scene(const Volume& vol, int size, const std::string& filter);

// The EGL context, shader cache and ray caster a benchmark renders with (the GL line printed).
struct BenchRenderer {
  std::unique_ptr<gpu::EglContext> context;
  std::unique_ptr<gpu::ShaderCache> shaders;
  std::unique_ptr<render::Raycaster> caster;
};
BenchRenderer make_bench_renderer();

}  // namespace peakcast::app
