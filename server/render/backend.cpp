#include "render/backend.h"

#include <cstdlib>
#include <stdexcept>

#include "cpu/cpu_renderer.h"
#include "render/raycaster.h"

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

std::string RenderBackend::description() const {
  // GL: the context's line (renderer, version, EGL platform); CPU: the SIMD target and threads.
  std::string d = std::string(to_string(backend)) + ": " + (context ? context->info().to_string() : renderer->description());
  if (!why.empty()) d += " (" + why + ")";
  return d;
}

RenderBackend open_backend(Backend requested, const std::string& egl_device, const std::filesystem::path& shader_dir) {
  RenderBackend b;
  if (requested == Backend::Cpu) {
    b.backend = Backend::Cpu;
    b.renderer = std::make_unique<cpu::CpuRenderer>();
    return b;
  }
  try {
    b.context = gpu::EglContext::create(egl_device);
  } catch (const std::exception& e) {
    if (requested == Backend::Gl) throw;
    b.backend = Backend::Cpu;
    b.why = std::string("auto: EGL failed: ") + e.what();
    b.renderer = std::make_unique<cpu::CpuRenderer>();
    return b;
  }
  if (requested == Backend::Auto && b.context->info().software) {
    b.backend = Backend::Cpu;
    b.why = "auto: EGL offers only " + b.context->info().renderer;
    b.context.reset();
    b.renderer = std::make_unique<cpu::CpuRenderer>();
    return b;
  }
  b.backend = Backend::Gl;
  if (requested == Backend::Auto) b.why = "auto: a hardware GL device";
  b.shaders = std::make_unique<gpu::ShaderCache>(shader_dir.empty() ? gpu::default_shader_dir() : shader_dir);
  b.renderer = std::make_unique<Raycaster>(*b.shaders);
  return b;
}

}  // namespace peakcast::render
