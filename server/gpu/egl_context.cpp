#include "gpu/egl_context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace peakcast::gpu {
namespace {

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)); p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

const EGLint kContextAttribs[] = {
    EGL_CONTEXT_MAJOR_VERSION,           4,       EGL_CONTEXT_MINOR_VERSION, 5, EGL_CONTEXT_OPENGL_PROFILE_MASK,
    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};

// Initialises `display` and creates a 4.5 core context; returns nullptr (and a reason) on failure.
EGLContext try_context(EGLDisplay display, std::string& why, EGLConfig& chosen) {
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    why = "eglInitialize failed";
    return EGL_NO_CONTEXT;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    why = "no desktop OpenGL API";
    return EGL_NO_CONTEXT;
  }
  EGLConfig config = nullptr;
  EGLint count = 0;
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  if (!eglChooseConfig(display, config_attribs, &config, 1, &count) || count == 0) {
    if (!has_extension(eglQueryString(display, EGL_EXTENSIONS), "EGL_KHR_no_config_context")) {
      why = "no OpenGL config";
      return EGL_NO_CONTEXT;
    }
    config = EGL_NO_CONFIG_KHR;
  }
  chosen = config;
  EGLContext ctx = eglCreateContext(display, config, EGL_NO_CONTEXT, kContextAttribs);
  if (ctx == EGL_NO_CONTEXT) why = "no OpenGL 4.5 core context";
  if (ctx != EGL_NO_CONTEXT && !eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    why = "cannot make the context current without a surface";
    eglDestroyContext(display, ctx);
    ctx = EGL_NO_CONTEXT;
  }
  if (ctx == EGL_NO_CONTEXT) eglTerminate(display);
  return ctx;
}

}  // namespace

std::string GlInfo::to_string() const {
  std::ostringstream s;
  s << renderer << " (" << vendor << "), OpenGL " << version << ", EGL " << platform << (software ? ", software" : "");
  return s.str();
}

// The process's rank on its node under an MPI launcher (Open MPI, Slurm, MPICH/Hydra, MVAPICH2,
// a PMIx launcher that exports it), or -1 outside one.
static int launcher_local_rank() {
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_RANK", "SLURM_LOCALID", "MPI_LOCALRANKID",
                           "MV2_COMM_WORLD_LOCAL_RANK", "PMIX_LOCAL_RANK"})
    if (const char* v = std::getenv(name); v && *v) return std::atoi(v);
  return -1;
}

std::unique_ptr<EglContext> EglContext::create(const std::string& device) {
  std::unique_ptr<EglContext> self(new EglContext());
  const char* env = std::getenv("PEAKCAST_EGL_DEVICE");
  const std::string choice = !device.empty() ? device : env && *env ? env : "auto";
  std::ostringstream tried;
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);

  if (choice != "surfaceless" && has_extension(client_ext, "EGL_EXT_device_enumeration") &&
      has_extension(client_ext, "EGL_EXT_platform_device")) {
    EGLDeviceEXT devices[32];
    EGLint n = 0;
    eglQueryDevicesEXT(32, devices, &n);
    // Hardware devices first (a GPU), software ones (llvmpipe's device) last.
    std::vector<int> order;
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < n; ++i) {
        const bool soft =
            has_extension(eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS), "EGL_MESA_device_software");
        if (soft == (pass == 1)) order.push_back(i);
      }
    // Distributed rendering (docs/distributed.md): with "auto", each rank of a node starts at its
    // own GPU (local rank modulo the hardware devices), the others left as fallbacks.
    const int local = launcher_local_rank();
    int hardware = 0;
    for (int i : order)
      hardware += !has_extension(eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS), "EGL_MESA_device_software");
    if (choice == "auto" && local > 0 && hardware > 1)
      std::rotate(order.begin(), order.begin() + local % hardware, order.begin() + hardware);
    for (int i : order) {
      if (choice != "auto" && choice != std::to_string(i)) continue;
      EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr);
      std::string why = "no display";
      EGLConfig config = nullptr;
      EGLContext ctx = d ? try_context(d, why, config) : EGL_NO_CONTEXT;
      const char* drm = has_extension(eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS), "EGL_EXT_device_drm")
                            ? eglQueryDeviceStringEXT(devices[i], EGL_DRM_DEVICE_FILE_EXT)
                            : nullptr;
      if (ctx != EGL_NO_CONTEXT) {
        self->display_ = d;
        self->context_ = ctx;
        self->config_ = config;
        self->info_.platform = "device " + std::to_string(i) + (drm ? std::string(" (") + drm + ")" : "");
        break;
      }
      tried << "device " << i << ": " << why << "; ";
    }
  }
  if (!self->context_ && (choice == "auto" || choice == "surfaceless")) {
    if (has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
      EGLDisplay d = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
      std::string why = "no display";
      EGLConfig config = nullptr;
      EGLContext ctx = d ? try_context(d, why, config) : EGL_NO_CONTEXT;
      if (ctx != EGL_NO_CONTEXT) {
        self->display_ = d;
        self->context_ = ctx;
        self->config_ = config;
        self->info_.platform = "surfaceless";
      } else {
        tried << "surfaceless: " << why << "; ";
      }
    } else {
      tried << "surfaceless: EGL_MESA_platform_surfaceless missing; ";
    }
  }
  if (!self->context_)
    throw std::runtime_error("no headless OpenGL 4.5 context (PEAKCAST_EGL_DEVICE=" + choice + "): " + tried.str() +
                             "install Mesa (libegl-mesa0, libgl1-mesa-dri) or a GPU driver");
  self->info_.vendor = reinterpret_cast<const char*>(glGetString(GL_VENDOR));
  self->info_.renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  self->info_.version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const std::string r = self->info_.renderer;
  self->info_.software = r.find("llvmpipe") != std::string::npos || r.find("softpipe") != std::string::npos;
  return self;
}

EglContext::~EglContext() {
  if (display_) {
    if (eglGetCurrentContext() == context_) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    if (owns_display_) eglTerminate(display_);
  }
}

std::unique_ptr<EglContext> EglContext::create_shared() const {
  EGLContext ctx = eglCreateContext(display_, config_, context_, kContextAttribs);
  if (ctx == EGL_NO_CONTEXT) throw std::runtime_error("no shared OpenGL context on this display");
  std::unique_ptr<EglContext> shared(new EglContext());
  shared->display_ = display_;
  shared->context_ = ctx;
  shared->config_ = config_;
  shared->owns_display_ = false;
  shared->info_ = info_;
  return shared;
}

void EglContext::make_current() {
  if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
    throw std::runtime_error("eglMakeCurrent failed");
}

}  // namespace peakcast::gpu
