// Headless OpenGL 4.5 core context through EGL: a real GPU found by device enumeration
// (EGL_EXT_device_enumeration + EGL_EXT_platform_device) when one exists, else Mesa's
// surfaceless platform (llvmpipe). Owns the display and context; current on the creating thread.
#pragma once

#include <memory>
#include <string>

namespace peakcast::gpu {

struct GlInfo {
  std::string vendor, renderer, version;
  std::string platform;  // "device N (drm path)" or "surfaceless"
  bool software = false;
  std::string to_string() const;
};

class EglContext {
 public:
  // Selection: env PEAKCAST_EGL_DEVICE = "auto" (default: hardware devices first), an index,
  // or "surfaceless". Throws std::runtime_error saying what was tried when nothing works.
  // device: "auto" (a GPU first, then software), "surfaceless", or a device index; empty: the
  // PEAKCAST_EGL_DEVICE variable, else auto.
  static std::unique_ptr<EglContext> create(const std::string& device = "");
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  const GlInfo& info() const { return info_; }
  void make_current();

 private:
  EglContext() = default;
  void* display_ = nullptr;
  void* context_ = nullptr;
  GlInfo info_;
};

}  // namespace peakcast::gpu
