#include "gpu/shader_cache.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

#include "core/log.h"

namespace fs = std::filesystem;

namespace peakcast::gpu {
namespace {

void expand_into(const fs::path& dir, const std::string& file, ExpandedSource& out, std::vector<std::string>& stack) {
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

ShaderCache::ShaderCache(fs::path dir, fs::path binaries, const EglContext* share)
    : dir_(std::move(dir)), share_(share) {
  const auto str = [](GLenum e) {
    const char* s = reinterpret_cast<const char*>(glGetString(e));
    return std::string(s ? s : "");
  };
  binaries_ = std::make_unique<ProgramBinaries>(std::move(binaries),
                                                str(GL_VENDOR) + "|" + str(GL_RENDERER) + "|" + str(GL_VERSION));
}

ShaderCache::~ShaderCache() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
    queue_.clear();
  }
  cv_.notify_all();
  if (worker_.joinable()) worker_.join();
}

Program ShaderCache::build(const Job& job, bool& loaded) {
  std::vector<ExpandedSource> sources;
  std::vector<std::string> texts;
  for (const auto& file : job.stages) {
    sources.push_back(expand_shader(dir_, file, job.defines));
    texts.push_back(file + "\n" + sources.back().text);
  }
  const std::string name = binaries_->name_of(texts);
  Program program(glCreateProgram());
  loaded = binaries_->load(name, program);
  if (loaded) return program;
  program = Program(glCreateProgram());  // a refused binary may leave the object unusable
  if (binaries_->enabled()) glProgramParameteri(program.id(), GL_PROGRAM_BINARY_RETRIEVABLE_HINT, GL_TRUE);
  std::vector<Shader> shaders;
  for (size_t k = 0; k < job.stages.size(); ++k) {
    const std::string& file = job.stages[k];
    Shader s(glCreateShader(stage_of(file)));
    const char* text = sources[k].text.c_str();
    glShaderSource(s.id(), 1, &text, nullptr);
    glCompileShader(s.id());
    if (std::string log = failure_log(s.id(), GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog); !log.empty())
      throw ShaderError("compiling " + file + " [" + job.key + "]:\n" + translate_log(log, sources[k].files));
    glAttachShader(program.id(), s.id());
    shaders.push_back(std::move(s));
  }
  glLinkProgram(program.id());
  if (std::string log = failure_log(program.id(), GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog); !log.empty())
    throw ShaderError("linking [" + job.key + "]: " + log);
  binaries_->save(name, program);
  return program;
}

const Program& ShaderCache::get(const std::string& key, const std::vector<std::string>& stages,
                                const std::vector<std::string>& defines) {
  std::unique_lock lock(m_);
  // Queued and not started: built here now. Being built in the background: waited for.
  queue_.erase(std::remove_if(queue_.begin(), queue_.end(), [&](const Job& j) { return j.key == key; }), queue_.end());
  cv_.wait(lock, [&] { return building_ != key; });
  if (auto it = programs_.find(key); it != programs_.end()) return it->second;
  failed_.erase(key);  // built again here, so its error reaches the caller
  lock.unlock();
  bool loaded = false;
  Program p = build(Job{key, stages, defines}, loaded);
  lock.lock();
  ++(loaded ? loads_ : compiles_);
  return programs_.emplace(key, std::move(p)).first->second;
}

void ShaderCache::prefetch(const std::string& key, const std::vector<std::string>& stages,
                           const std::vector<std::string>& defines) {
  if (!share_) return;
  std::lock_guard lock(m_);
  if (stop_ || programs_.count(key) || failed_.count(key) || building_ == key) return;
  for (const Job& j : queue_)
    if (j.key == key) return;
  queue_.push_back(Job{key, stages, defines});
  if (!worker_.joinable()) {
    std::unique_ptr<EglContext> context;
    try {
      context = share_->create_shared();
    } catch (const std::exception& e) {
      log::warn(std::string("shader prefetch off: ") + e.what());
      share_ = nullptr;
      queue_.clear();
      return;
    }
    worker_ = std::thread([this, c = std::move(context)]() mutable { worker_loop(std::move(c)); });
  }
  cv_.notify_all();
}

void ShaderCache::worker_loop(std::unique_ptr<EglContext> context) {
  context->make_current();
  std::unique_lock lock(m_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (stop_) break;
    Job job = std::move(queue_.front());
    queue_.pop_front();
    building_ = job.key;
    lock.unlock();
    std::string error;
    Program p;
    bool loaded = false;
    try {
      p = build(job, loaded);
      glFinish();  // linked before another context uses it
    } catch (const std::exception& e) {
      error = e.what();
    }
    lock.lock();
    building_.clear();
    if (error.empty()) {
      ++background_;
      if (loaded) ++loads_;
      programs_.emplace(job.key, std::move(p));
    } else {
      failed_.emplace(job.key, error);
    }
    cv_.notify_all();
  }
  lock.unlock();
  context.reset();  // destroyed on the thread it was current on
}

bool ShaderCache::ready(const std::string& key) const {
  std::lock_guard lock(m_);
  return programs_.count(key) != 0;
}

size_t ShaderCache::size() const {
  std::lock_guard lock(m_);
  return programs_.size();
}

size_t ShaderCache::compiles() const {
  std::lock_guard lock(m_);
  return compiles_;
}

size_t ShaderCache::background_builds() const {
  std::lock_guard lock(m_);
  return background_;
}

size_t ShaderCache::loads() const {
  std::lock_guard lock(m_);
  return loads_;
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
