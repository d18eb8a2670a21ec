#include "gpu/gl_device.h"

#include "gpu/shader_cache.h"
#include "gpu/gl_renderer.h"

namespace peakcast::gpu {

using namespace render;  // the renderer interface and frame setup this implements
namespace {

class EglDevice final : public GlDevice {
 public:
  explicit EglDevice(std::unique_ptr<gpu::EglContext> context) : context_(std::move(context)) {}
  const gpu::GlInfo& info() const override { return context_->info(); }
  std::string description() const override { return context_->info().to_string(); }
  std::unique_ptr<Renderer> make_renderer(const std::filesystem::path& shader_dir,
                                          const std::filesystem::path& program_cache) override {
    shaders_ = std::make_unique<gpu::ShaderCache>(shader_dir.empty() ? gpu::default_shader_dir() : shader_dir,
                                                  program_cache, context_.get());
    return std::make_unique<GlRenderer>(*shaders_);
  }
  ShaderCache* shaders() override { return shaders_.get(); }
  ~EglDevice() override {
    shaders_.reset();  // programs go while their context is still there
    context_.reset();
  }

 private:
  std::unique_ptr<gpu::EglContext> context_;
  std::unique_ptr<gpu::ShaderCache> shaders_;
};

}  // namespace

std::unique_ptr<GlDevice> open_gl_device(const std::string& egl_device) {
  return std::make_unique<EglDevice>(gpu::EglContext::create(egl_device));
}

std::filesystem::path gl_shader_dir() { return gpu::default_shader_dir(); }

std::filesystem::path gl_program_cache_dir() { return gpu::default_program_cache_dir(); }

}  // namespace peakcast::gpu
