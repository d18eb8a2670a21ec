#include "gpu/uniform_layout.h"

namespace peakcast::gpu {

std::map<std::string, size_t> uniform_offsets(const gpu::Program& program) {
  std::map<std::string, size_t> out;
  const GLuint block = glGetProgramResourceIndex(program.id(), GL_UNIFORM_BLOCK, "RayUniforms");
  if (block == GL_INVALID_INDEX) return out;
  const GLenum count_prop = GL_NUM_ACTIVE_VARIABLES;
  GLint count = 0;
  glGetProgramResourceiv(program.id(), GL_UNIFORM_BLOCK, block, 1, &count_prop, 1, nullptr, &count);
  std::vector<GLint> members(size_t(std::max(count, 0)));
  const GLenum members_prop = GL_ACTIVE_VARIABLES;
  glGetProgramResourceiv(program.id(), GL_UNIFORM_BLOCK, block, 1, &members_prop, count, nullptr, members.data());
  for (GLint m : members) {
    char name[128];
    glGetProgramResourceName(program.id(), GL_UNIFORM, GLuint(m), sizeof name, nullptr, name);
    const GLenum offset_prop = GL_OFFSET;
    GLint offset = -1;
    glGetProgramResourceiv(program.id(), GL_UNIFORM, GLuint(m), 1, &offset_prop, 1, nullptr, &offset);
    out[name] = size_t(offset);
  }
  return out;
}

size_t uniform_block_size(const gpu::Program& program) {
  const GLuint block = glGetProgramResourceIndex(program.id(), GL_UNIFORM_BLOCK, "RayUniforms");
  const GLenum prop = GL_BUFFER_DATA_SIZE;
  GLint size = 0;
  glGetProgramResourceiv(program.id(), GL_UNIFORM_BLOCK, block, 1, &prop, 1, nullptr, &size);
  return size_t(size);
}

}  // namespace peakcast::gpu
