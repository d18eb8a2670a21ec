#include "gpu/shader_cache.h"

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

namespace fs = std::filesystem;

namespace peakcast::gpu {
namespace {

void expand_into(const fs::path& dir, const std::string& file, ExpandedSource& out,
                 std::vector<std::string>& stack) {
  for (const auto& f : stack)
    if (f == file) throw ShaderError("shader include cycle at " + file);
  std::ifstream in(dir / file);
  if (!in) throw ShaderError("shader file not found: " + (dir / file).string());
  stack.push_back(file);
  const int index = int(out.files.size());
  out.files.push_back(file);
  out.text += "#line 1 " + std::to_string(index) + "\n";
  static const std::regex include_re(R"(^\s*#include\s+"([^"]+)\"\s*$)");
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    std::smatch m;
    if (std::regex_match(line, m, include_re)) {
      expand_into(dir, m[1].str(), out, stack);
      out.text += "#line " + std::to_string(n + 1) + " " + std::to_string(index) + "\n";
    } else {
      out.text += line + "\n";
    }
  }
  stack.pop_back();
}

// Empty when `status` reports success, else the object's info log (shaders and programs alike).
template <typename GetIv, typename GetLog>
std::string failure_log(GLuint id, GLenum status, GetIv get_iv, GetLog get_log) {
  GLint ok = 0;
  get_iv(id, status, &ok);
  if (ok) return "";
  GLint len = 0;
  get_iv(id, GL_INFO_LOG_LENGTH, &len);
  std::string log(size_t(std::max(len, 1)), '\0');
  get_log(id, len, nullptr, log.data());
  log.resize(std::strlen(log.c_str()));
  return log.empty() ? "(no log)" : log;
}

GLenum stage_of(const std::string& file) {
  if (file.ends_with(".vert")) return GL_VERTEX_SHADER;
  if (file.ends_with(".frag")) return GL_FRAGMENT_SHADER;
  if (file.ends_with(".comp")) return GL_COMPUTE_SHADER;
  throw ShaderError("unknown shader stage for " + file);
}

}  // namespace

ExpandedSource expand_shader(const fs::path& dir, const std::string& file, const std::vector<std::string>& defines) {
  ExpandedSource out;
  out.text = "#version 450 core\n";
  for (const auto& d : defines) out.text += "#define " + d + "\n";
  std::vector<std::string> stack;
  expand_into(dir, file, out, stack);
  return out;
}

std::string translate_log(const std::string& log, const std::vector<std::string>& files) {
  static const std::regex mesa(R"((\d+):(\d+)\(\d+\))"), nvidia(R"((\d+)\((\d+)\))");
  std::string out;
  std::istringstream in(log);
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, mesa) || std::regex_search(line, m, nvidia)) {
      size_t idx = std::stoul(m[1].str());
      if (idx < files.size()) line = m.prefix().str() + files[idx] + ":" + m[2].str() + m.suffix().str();
    }
    out += line + "\n";
  }
  return out;
}

const Program& ShaderCache::get(const std::string& key, const std::vector<std::string>& stages,
                                const std::vector<std::string>& defines) {
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;
  ++compiles_;
  Program program(glCreateProgram());
  std::vector<Shader> shaders;
  for (const auto& file : stages) {
    ExpandedSource src = expand_shader(dir_, file, defines);
    Shader s(glCreateShader(stage_of(file)));
    const char* text = src.text.c_str();
    glShaderSource(s.id(), 1, &text, nullptr);
    glCompileShader(s.id());
    if (std::string log = failure_log(s.id(), GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog); !log.empty())
      throw ShaderError("compiling " + file + " [" + key + "]:\n" + translate_log(log, src.files));
    glAttachShader(program.id(), s.id());
    shaders.push_back(std::move(s));
  }
  glLinkProgram(program.id());
  if (std::string log = failure_log(program.id(), GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog); !log.empty())
    throw ShaderError("linking [" + key + "]: " + log);
  return programs_.emplace(key, std::move(program)).first->second;
}

fs::path default_shader_dir() {
  if (const char* env = std::getenv("PEAKCAST_SHADER_DIR"); env && *env) return env;
#ifdef PEAKCAST_SHADER_DIR_DEFAULT
  return PEAKCAST_SHADER_DIR_DEFAULT;
#else
  return "shaders";
#endif
}

}  // namespace peakcast::gpu
