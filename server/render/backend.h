// Which ray caster draws (docs/performance.md): "gl", the GL ray caster through EGL;
// "cpu", the native CPU backend (cpu/); "auto" (the default), the CPU backend when EGL offers
// only a software rasteriser (Mesa's llvmpipe or softpipe) and the GL one on a real GPU.
// PEAKCAST_BACKEND sets it for every command; the CLI's and the server's --backend override.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "gpu/gl_device.h"
#include "render/renderer.h"

namespace peakcast::render {

enum class Backend { Auto, Gl, Cpu };

// "auto", "gl" or "cpu"; throws std::invalid_argument naming the choices.
Backend parse_backend(const std::string& name);
const char* to_string(Backend b);
// `name` empty: PEAKCAST_BACKEND, else auto.
Backend requested_backend(const std::string& name = "");

// Whether this build has the GL ray caster (PEAKCAST_WITH_GL); without it every backend is
// the CPU one, and asking for gl is refused by name.
bool gl_built();

// A renderer and what it needs. The GL device is opened for gl and auto (auto reads it to
// decide) and kept only for gl; a forced cpu backend opens no EGL display at all.
struct RenderBackend {
  Backend backend = Backend::Gl;          // resolved: gl or cpu
  std::unique_ptr<gpu::GlDevice> device;  // gl only; outlives the renderer (declared first)
  std::unique_ptr<Renderer> renderer;
  std::string why;  // how auto chose (empty for a forced backend)
  // One line for logs and stats: "gl: <GL renderer>" or "cpu: AVX3, 2 threads (...)".
  std::string description() const;
};

// Throws std::runtime_error when the requested backend cannot start (gl without a context, or
// a build without GL). With auto, a machine where EGL cannot start at all renders on the CPU
// (said in `why`).
// program_cache: where GL keeps linked programs as driver binaries: a folder, "off", "auto" (the
// default, ~/.cache/peakcast/programs), or empty for PEAKCAST_PROGRAM_CACHE, else auto.
RenderBackend open_backend(Backend requested, const std::string& egl_device = "",
                           const std::filesystem::path& shader_dir = {}, const std::string& program_cache = "");
// The program cache's folder for a choice as open_backend takes it (empty: off).
std::filesystem::path program_cache_dir(const std::string& choice);

// The shaders' folder of GL builds ($PEAKCAST_SHADER_DIR, else the source tree's); empty
// without GL.
std::filesystem::path default_shader_dir();

}  // namespace peakcast::render
