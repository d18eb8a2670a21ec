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
  if (GLenum e = glGetError(); e != GL_NO_ERROR)
    char code[16];
    std::snprintf(code, sizeof code, "0x%04x", unsigned(e));
    throw std::runtime_error(std::string("GL error ") + code + " after " + what);
}
#endif

}  // namespace peakcast::gpu
