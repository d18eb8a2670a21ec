#include "render/backend.h"

#include <cstdlib>
#include <stdexcept>

#include "cpu/cpu_renderer.h"

namespace peakcast::render {

Backend parse_backend(const std::string& name) {
  if (name == "auto") return Backend::Auto;
  if (name == "gl") return Backend::Gl;
  if (name == "cpu") return Backend::Cpu;
  throw std::invalid_argument("unknown backend '" + name + "': choose auto, gl or cpu");
}

const char* to_string(Backend b) {
  switch (b) {
    case Backend::Auto: return "auto";
    case Backend::Gl: return "gl";
    case Backend::Cpu: return "cpu";
  }
  return "auto";
}

Backend requested_backend(const std::string& name) {
  if (!name.empty()) return parse_backend(name);
  const char* env = std::getenv("PEAKCAST_BACKEND");
  if (env && *env) {
    try {
      return parse_backend(env);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("PEAKCAST_BACKEND: ") + e.what());
    }
  }
  return Backend::Auto;
}

bool gl_built() {
#ifdef PEAKCAST_HAVE_GL
  return true;
#else
  return false;
#endif
}

std::filesystem::path default_shader_dir() {
#ifdef PEAKCAST_HAVE_GL
  return gpu::gl_shader_dir();
#else
  return {};
#endif
}

std::string RenderBackend::description() const {
  // GL: the context's line (renderer, version, EGL platform); CPU: the SIMD target and threads.
  std::string d = std::string(to_string(backend)) + ": " + (device ? device->description() : renderer->description());
  if (!why.empty()) d += " (" + why + ")";
  return d;
}

std::filesystem::path program_cache_dir(const std::string& choice) {
  std::string c = choice;
  if (c.empty())
    if (const char* env = std::getenv("PEAKCAST_PROGRAM_CACHE"); env && *env) c = env;
  if (c == "off") return {};
  if (!c.empty() && c != "auto") return c;
#ifdef PEAKCAST_HAVE_GL
  return gpu::gl_program_cache_dir();
#else
  return {};
#endif
}

RenderBackend open_backend(Backend requested, const std::string& egl_device, const std::filesystem::path& shader_dir,
                           const std::string& program_cache) {
  RenderBackend b;
  auto on_cpu = [&b](std::string why) -> RenderBackend& {
    b.backend = Backend::Cpu;
    b.why = std::move(why);
    b.device.reset();
    b.renderer = std::make_unique<cpu::CpuRenderer>();
    return b;
  };
  if (requested == Backend::Cpu) return std::move(on_cpu(""));
#ifdef PEAKCAST_HAVE_GL
  try {
    b.device = gpu::open_gl_device(egl_device);
  } catch (const std::exception& e) {
    if (requested == Backend::Gl) throw;
    return std::move(on_cpu(std::string("auto: EGL failed: ") + e.what()));
  }
  if (requested == Backend::Auto && b.device->info().software)
    return std::move(on_cpu("auto: EGL offers only " + b.device->info().renderer));
  b.backend = Backend::Gl;
  if (requested == Backend::Auto) b.why = "auto: a hardware GL device";
  b.renderer = b.device->make_renderer(shader_dir, program_cache_dir(program_cache));
  return b;
#else
  (void)egl_device;
  (void)shader_dir;
  (void)program_cache;
  if (requested == Backend::Gl)
    throw std::runtime_error(
        "backend gl: this peakcast was built without GL (PEAKCAST_WITH_GL=OFF): use --backend cpu");
  return std::move(on_cpu("auto: built without GL"));
#endif
}

}  // namespace peakcast::render
