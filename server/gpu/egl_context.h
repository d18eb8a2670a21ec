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
  // A second context on this display that shares this one's objects (a program linked there is
  // usable here), for another thread to make current; it must be destroyed before this one.
  // Throws std::runtime_error when the driver refuses.
  std::unique_ptr<EglContext> create_shared() const;

 private:
  EglContext() = default;
  void* display_ = nullptr;
  void* context_ = nullptr;
  void* config_ = nullptr;
  bool owns_display_ = true;  // false for a shared context: the first one terminates the display
  GlInfo info_;
};

}  // namespace peakcast::gpu
