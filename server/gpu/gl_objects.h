// Move-only owners for GL objects. GL names never leave server/gpu.
#pragma once

#include <epoxy/gl.h>

#include <utility>

namespace peakcast::gpu {

template <void (*Delete)(GLuint)>
class GlObject {
 public:
  GlObject() = default;
  explicit GlObject(GLuint id) : id_(id) {}
  ~GlObject() { reset(); }
  GlObject(GlObject&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlObject& operator=(GlObject&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;

  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }
  void reset() {
    if (id_) Delete(id_);
    id_ = 0;
  }

 private:
  GLuint id_ = 0;
};

namespace detail {
inline void delete_texture(GLuint id) { glDeleteTextures(1, &id); }
inline void delete_buffer(GLuint id) { glDeleteBuffers(1, &id); }
inline void delete_framebuffer(GLuint id) { glDeleteFramebuffers(1, &id); }
inline void delete_vertex_array(GLuint id) { glDeleteVertexArrays(1, &id); }
inline void delete_program(GLuint id) { glDeleteProgram(id); }
inline void delete_shader(GLuint id) { glDeleteShader(id); }
inline void delete_query(GLuint id) { glDeleteQueries(1, &id); }
}  // namespace detail

using Texture = GlObject<detail::delete_texture>;
using Buffer = GlObject<detail::delete_buffer>;
using Framebuffer = GlObject<detail::delete_framebuffer>;
using VertexArray = GlObject<detail::delete_vertex_array>;
using Program = GlObject<detail::delete_program>;
using Shader = GlObject<detail::delete_shader>;
using Query = GlObject<detail::delete_query>;

// A fence (GLsync is a pointer, not a name): owned like the names above.
class Fence {
 public:
  Fence() = default;
  explicit Fence(GLsync sync) : sync_(sync) {}
  ~Fence() { reset(); }
  Fence(Fence&& o) noexcept : sync_(std::exchange(o.sync_, nullptr)) {}
  Fence& operator=(Fence&& o) noexcept {
    if (this != &o) {
      reset();
      sync_ = std::exchange(o.sync_, nullptr);
    }
    return *this;
  }
  Fence(const Fence&) = delete;
  Fence& operator=(const Fence&) = delete;
  GLsync get() const { return sync_; }
  explicit operator bool() const { return sync_ != nullptr; }
  void reset() {
    if (sync_) glDeleteSync(sync_);
    sync_ = nullptr;
  }

 private:
  GLsync sync_ = nullptr;
};

Texture make_texture(GLenum target);
Buffer make_buffer();
Query make_query(GLenum target);  // e.g. GL_TIMESTAMP

// The GPU's time for a span of commands: a timestamp before and one after (a GL_TIME_ELAPSED
// query reads 0 or a raw timestamp on llvmpipe; timestamps are right everywhere).
struct GpuTimer {
  Query begin, end;
  static GpuTimer make();
  void start() const { glQueryCounter(begin.id(), GL_TIMESTAMP); }
  void stop() const { glQueryCounter(end.id(), GL_TIMESTAMP); }
  double elapsed_ms() const;  // waits for both results
};
// A fence after every command issued so far, and the commands flushed so it will signal.
Fence fence_now();
Framebuffer make_framebuffer();
VertexArray make_vertex_array();

// Debug builds only: throws with `what` when glGetError reports an error.
#ifndef NDEBUG
void check_gl(const char* what);
#else
inline void check_gl(const char*) {}
#endif

}  // namespace peakcast::gpu
