#include "gl/gl_device.h"

#include "gl/shader_cache.h"
#include "gl/gl_renderer.h"

namespace peakcast::gl {

using namespace render;  // the renderer interface and frame setup this implements
namespace {

class EglDevice final : public GlDevice {
 public:
  explicit EglDevice(std::unique_ptr<gl::EglContext> context) : context_(std::move(context)) {}
  const gl::GlInfo& info() const override { return context_->info(); }
  std::string description() const override { return context_->info().to_string(); }
  std::unique_ptr<Renderer> make_renderer(const std::filesystem::path& shader_dir,
                                          const std::filesystem::path& program_cache) override {
    shaders_ = std::make_unique<gl::ShaderCache>(shader_dir.empty() ? gl::default_shader_dir() : shader_dir,
                                                  program_cache, context_.get());
    return std::make_unique<GlRenderer>(*shaders_);
  }
  ~EglDevice() override {
    shaders_.reset();  // programs go while their context is still there
    context_.reset();
  }

 private:
  std::unique_ptr<gl::EglContext> context_;
  std::unique_ptr<gl::ShaderCache> shaders_;
};

}  // namespace

std::unique_ptr<GlDevice> open_gl_device(const std::string& egl_device) {
  return std::make_unique<EglDevice>(gl::EglContext::create(egl_device));
}

std::filesystem::path gl_shader_dir() { return gl::default_shader_dir(); }

std::filesystem::path gl_program_cache_dir() { return gl::default_program_cache_dir(); }

}  // namespace peakcast::gl
