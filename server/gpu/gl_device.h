// The GL side of choosing a backend (render/backend.h): an EGL context on a device and the GL
// ray caster made on it. Only GL builds (PEAKCAST_WITH_GL) define open_gl_device; the
// interface itself holds no GL type, so the choice compiles and links without GL.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "gpu/egl_context.h"  // GlInfo: strings only
#include "render/renderer.h"

namespace peakcast::gpu {

class ShaderCache;

class GlDevice {
 public:
  virtual ~GlDevice() = default;
  virtual const gpu::GlInfo& info() const = 0;
  virtual std::string description() const = 0;  // renderer, version and EGL platform, one line
  // The GL ray caster on this device (shaders from `shader_dir`, linked programs kept as driver
  // binaries in `program_cache`, empty: off); the device must outlive it.
  virtual std::unique_ptr<render::Renderer> make_renderer(const std::filesystem::path& shader_dir,
                                                          const std::filesystem::path& program_cache) = 0;
  // The shaders make_renderer loaded (null before): another GL renderer on this device shares
  // them (peakcast-bench's, with its bare sampling loop).
  virtual ShaderCache* shaders() = 0;
};

// An EGL context on `egl_device` ("auto", "surfaceless", an index; empty: PEAKCAST_EGL_DEVICE,
// else auto), current on this thread. Throws std::runtime_error saying what was tried.
std::unique_ptr<GlDevice> open_gl_device(const std::string& egl_device);

// The shaders' folder: $PEAKCAST_SHADER_DIR, else the source tree's.
std::filesystem::path gl_shader_dir();
// The program cache's default folder ($XDG_CACHE_HOME or ~/.cache, then peakcast/programs).
std::filesystem::path gl_program_cache_dir();

}  // namespace peakcast::gpu
