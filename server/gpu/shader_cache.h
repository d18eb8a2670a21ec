// Loads GLSL files from shaders/, prepends #version and the variant's #defines, expands
// #include "file" with #line markers (so errors name file and line), and caches linked programs
// by variant key.
#pragma once

#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "gpu/gl_objects.h"

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

class ShaderCache {
 public:
  explicit ShaderCache(std::filesystem::path dir) : dir_(std::move(dir)) {}

  // stages: file names ending in .vert / .frag / .comp; compiled and linked once per key.
  const Program& get(const std::string& key, const std::vector<std::string>& stages,
                     const std::vector<std::string>& defines);
  size_t size() const { return programs_.size(); }
  size_t compiles() const { return compiles_; }  // programs compiled and linked so far (cache misses)
  const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  std::map<std::string, Program> programs_;
  size_t compiles_ = 0;
};

// Default shader directory: $PEAKCAST_SHADER_DIR, else the one next to the source tree.
std::filesystem::path default_shader_dir();

}  // namespace peakcast::gpu
