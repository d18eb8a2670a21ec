#include "gpu/compute_table.h"

#include <algorithm>

namespace peakcast::gpu {

std::vector<float> run_compute_table(const Program& program, const ComputeTable& t) {
  Buffer ubo, in, out;
  if (t.uniforms) {
    ubo = make_buffer();
    glNamedBufferStorage(ubo.id(), GLsizeiptr(t.uniform_bytes), t.uniforms, 0);
    glBindBufferBase(GL_UNIFORM_BUFFER, t.ubo_binding, ubo.id());
  }
  in = make_buffer();
  glNamedBufferStorage(in.id(), GLsizeiptr(std::max<size_t>(t.in.size(), 1) * sizeof(float)), t.in.data(), 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, t.in_binding, in.id());
  std::vector<float> result(t.out_floats, 0.f);
  out = make_buffer();
  glNamedBufferStorage(out.id(), GLsizeiptr(std::max<size_t>(result.size(), 1) * sizeof(float)), result.data(),
                       GL_DYNAMIC_STORAGE_BIT);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, t.out_binding, out.id());
  glUseProgram(program.id());
  glDispatchCompute(GLuint((t.rows + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetNamedBufferSubData(out.id(), 0, GLsizeiptr(result.size() * sizeof(float)), result.data());
  glUseProgram(0);
  return result;
}

}  // namespace peakcast::gpu
