// Where the server may read files: every path a reader opens (a volume, its detached data file,
// a chunk, a pyramid level, a sidecar, a ray-texture PNG) is resolved, links followed, and must
// lie inside one of these roots, at every open, not only in listings. A link out of a data
// directory is refused wherever it stands. Like OpenBSD's unveil(): set once when the server
// starts (data directories, the upload folder, the operator's preloaded volumes' folders); command-line
// tools that read what their user names set nothing and are not confined.
#pragma once

#include <filesystem>
#include <vector>

namespace peakcast::file_roots {

// Replaces the roots (each resolved now). An empty list: no confinement.
void confine(const std::vector<std::filesystem::path>& roots);
bool confined();

// Throws VolumeError naming `path`'s file name when confinement is on and `path`, resolved
// (symbolic links followed, `..` removed), lies outside every root: "lies outside the data
// directories". A path that does not exist is checked as far as it resolves.
void check(const std::filesystem::path& path);

// Restores the previous roots when it goes (tests).
class Scope {
 public:
  explicit Scope(const std::vector<std::filesystem::path>& roots);
  ~Scope();
  Scope(const Scope&) = delete;
  Scope& operator=(const Scope&) = delete;

 private:
  std::vector<std::filesystem::path> saved_;
};

}  // namespace peakcast::file_roots
