// Linked programs kept on disk as the driver's own binaries (glGetProgramBinary), so a variant
// compiled once is loaded in milliseconds by a later process. A file is named by a hash of the
// driver's identity (vendor, renderer, version) and every stage's expanded source: a new
// driver or a changed shader never loads an old binary. A binary the driver refuses (or a
// truncated file) is ignored and compiled again; files are written whole or not at all.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "gpu/gl_objects.h"

namespace peakcast::gpu {

class ProgramBinaries {
 public:
  // `dir` empty: off (load finds nothing, save keeps nothing). The folder is made when first
  // written; one that cannot be written turns saving off, said once in the log.
  ProgramBinaries(std::filesystem::path dir, std::string driver_identity);
  bool enabled() const { return !dir_.empty(); }
  const std::filesystem::path& dir() const { return dir_; }

  // The file name for a program of these stages' sources.
  std::string name_of(const std::vector<std::string>& sources) const;
  // Loads `name` into `program` (a fresh program object); false when absent or refused.
  bool load(const std::string& name, const Program& program) const;
  // Saves a linked program (linked with GL_PROGRAM_BINARY_RETRIEVABLE_HINT).
  void save(const std::string& name, const Program& program);

 private:
  std::filesystem::path dir_;
  std::string identity_;
  bool warned_ = false;
};

// The default folder: $XDG_CACHE_HOME/peakcast/programs, else ~/.cache/peakcast/programs; empty
// when neither is known.
std::filesystem::path default_program_cache_dir();

}  // namespace peakcast::gpu
