#include "gpu/gl_objects.h"

#include <cstdio>
#include <stdexcept>
#include <string>

namespace peakcast::gpu {

Texture make_texture(GLenum target) {
  GLuint id = 0;
  glCreateTextures(target, 1, &id);
  return Texture(id);
}

Buffer make_buffer() {
  GLuint id = 0;
  glCreateBuffers(1, &id);
  return Buffer(id);
}

Query make_query(GLenum target) {
  GLuint id = 0;
  glCreateQueries(target, 1, &id);
  return Query(id);
}

GpuTimer GpuTimer::make() { return GpuTimer{make_query(GL_TIMESTAMP), make_query(GL_TIMESTAMP)}; }

double GpuTimer::elapsed_ms() const {
  GLuint64 a = 0, b = 0;
  glGetQueryObjectui64v(begin.id(), GL_QUERY_RESULT, &a);
  glGetQueryObjectui64v(end.id(), GL_QUERY_RESULT, &b);
  return b > a ? double(b - a) * 1e-6 : 0.0;
}

Fence fence_now() {
  Fence f(glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
  glFlush();
  return f;
}

Framebuffer make_framebuffer() {
  GLuint id = 0;
  glCreateFramebuffers(1, &id);
  return Framebuffer(id);
}

VertexArray make_vertex_array() {
  GLuint id = 0;
  glCreateVertexArrays(1, &id);
  return VertexArray(id);
}

#ifndef NDEBUG
void check_gl(const char* what) {
  if (GLenum e = glGetError(); e != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", unsigned(e));
    throw std::runtime_error(std::string("GL error ") + code + " after " + what);
  }
}
#endif

}  // namespace peakcast::gpu
