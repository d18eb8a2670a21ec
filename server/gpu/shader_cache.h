// Loads GLSL files from shaders/, prepends #version and the variant's #defines, expands
// #include "file" with #line markers (so errors name file and line), and caches linked programs
// by variant key, in memory and (as driver binaries) on disk.
#pragma once

#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "gpu/egl_context.h"
#include "gpu/gl_objects.h"
#include "gpu/program_binaries.h"

namespace peakcast::gpu {

class ShaderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ExpandedSource {
  std::string text;
  std::vector<std::string> files;  // #line source-string number -> file name
};

// Reads `file` from `dir`; throws ShaderError for missing files or include cycles.
ExpandedSource expand_shader(const std::filesystem::path& dir, const std::string& file,
                             const std::vector<std::string>& defines);

// Rewrites driver messages "0:12(3): error" / "0(12) : error" to "file.glsl:12: error".
std::string translate_log(const std::string& log, const std::vector<std::string>& files);

// Programs by variant key. A program is built (its binary loaded from the program cache, or its
// stages compiled and linked, then saved there) the first time it is asked for, on the calling
// thread, or earlier on a background thread with a shared context when prefetch() names it:
// get() then finds it ready, or waits only for the rest of its build.
class ShaderCache {
 public:
  // binaries: the program cache's folder (empty: off). share: the render thread's context;
  // with one, prefetch() builds on a thread of its own, else prefetch() does nothing.
  explicit ShaderCache(std::filesystem::path dir, std::filesystem::path binaries = {},
                       const EglContext* share = nullptr);
  ~ShaderCache();
  ShaderCache(const ShaderCache&) = delete;
  ShaderCache& operator=(const ShaderCache&) = delete;

  // stages: file names ending in .vert / .frag / .comp; built once per key.
  const Program& get(const std::string& key, const std::vector<std::string>& stages,
                     const std::vector<std::string>& defines);
  // Builds the program in the background unless it is built or queued already.
  void prefetch(const std::string& key, const std::vector<std::string>& stages,
                const std::vector<std::string>& defines);
  bool ready(const std::string& key) const;  // built, here or in the background
  size_t size() const;
  size_t compiles() const;           // programs compiled and linked on the calling thread
  size_t background_builds() const;  // programs built by prefetch (loaded or compiled)
  size_t loads() const;              // programs loaded from the program cache, anywhere
  const std::filesystem::path& dir() const { return dir_; }

 private:
  struct Job {
    std::string key;
    std::vector<std::string> stages, defines;
  };
  Program build(const Job& job, bool& loaded);  // on the thread whose context is current
  void worker_loop(std::unique_ptr<EglContext> context);

  std::filesystem::path dir_;
  std::unique_ptr<ProgramBinaries> binaries_;
  const EglContext* share_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::map<std::string, Program> programs_;    // built, usable here
  std::map<std::string, std::string> failed_;  // background builds that failed: their error
  std::deque<Job> queue_;
  std::string building_;  // the key the worker builds now
  size_t compiles_ = 0, background_ = 0, loads_ = 0;
  bool stop_ = false;
  std::thread worker_;
};

// Default shader directory: $PEAKCAST_SHADER_DIR, else the one next to the source tree.
std::filesystem::path default_shader_dir();

}  // namespace peakcast::gpu
