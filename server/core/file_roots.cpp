#include "core/file_roots.h"

#include <cstdint>
#include <mutex>
#include <shared_mutex>

#include "core/dicom.h"
#include "core/volume_io.h"

namespace fs = std::filesystem;

namespace peakcast::file_roots {
namespace {

std::shared_mutex m;
std::vector<fs::path> roots;  // resolved
uint64_t generation = 1;      // changes with the roots: a thread's cached folder is checked anew

fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(p, ec);
  if (ec) r = fs::absolute(p, ec).lexically_normal();
  return r;
}

bool inside(const fs::path& p, const fs::path& root) {
  auto pi = p.begin();
  for (auto ri = root.begin(); ri != root.end(); ++ri, ++pi) {
    if (ri->empty()) continue;  // a trailing separator
    if (pi == p.end() || *pi != *ri) return false;
  }
  return true;
}

}  // namespace

void confine(const std::vector<fs::path>& list) {
  std::vector<fs::path> r;
  for (const auto& p : list) r.push_back(resolved(p));
  std::unique_lock lock(m);
  roots = std::move(r);
  ++generation;
}

bool confined() {
  std::shared_lock lock(m);
  return !roots.empty();
}

namespace {

bool inside_any(const fs::path& r) {
  for (const auto& root : roots)
    if (inside(r, root)) return true;
  return false;
}

[[noreturn]] void refuse(const fs::path& path) {
  throw VolumeError(path.filename(), "lies outside the data directories (a link out of them is refused)");
}

}  // namespace

void check(const fs::path& path) {
  std::shared_lock lock(m);
  if (roots.empty()) return;
  // A chunked volume opens thousands of files in one folder: the folder is resolved once per
  // thread and kept while the roots stand; the file itself is looked at every time (a link is
  // resolved whole). Missing files cost one lstat.
  thread_local fs::path last_dir, last_dir_resolved;
  thread_local uint64_t last_generation = 0;
  const fs::path abs = path.is_absolute() ? path : fs::absolute(path);
  const fs::path dir = abs.parent_path();
  if (dir != last_dir || last_generation != generation) {
    last_dir_resolved = resolved(dir);
    last_dir = dir;
    last_generation = generation;
  }
  std::error_code ec;
  const auto st = fs::symlink_status(abs, ec);
  fs::path r;
  if (fs::is_symlink(st))
    r = resolved(abs);
  else if (abs.filename() == ".." || abs.filename() == ".")
    r = resolved(abs);
  else
    r = last_dir_resolved / abs.filename();
  if (!inside_any(r)) refuse(path);
}

Scope::Scope(const std::vector<fs::path>& list) {
  {
    std::shared_lock lock(m);
    saved_ = roots;
  }
  confine(list);
}

Scope::~Scope() {
  std::unique_lock lock(m);
  roots = std::move(saved_);
  ++generation;
}

}  // namespace peakcast::file_roots

namespace peakcast {

fs::path resolve_in_roots(const fs::path& requested, const std::vector<fs::path>& roots) {
  if (roots.empty()) throw VolumeError(requested, "no data directory is configured");
  auto inside = [](const fs::path& p, const fs::path& root) {
    auto rel = p.lexically_relative(root);
    return !rel.empty() && *rel.begin() != "..";
  };
  for (const auto& root : roots) {
    std::error_code ec;
    fs::path r = fs::weakly_canonical(root, ec);
    fs::path candidate = requested.is_absolute() ? requested : r / requested;
    fs::path c = fs::weakly_canonical(candidate, ec);  // resolves .. and symlinks
    if (ec || !inside(c, r)) continue;
    if (fs::exists(c, ec) || fs::is_directory(dicom::split_series_path(c).folder, ec)) return c;  // or FOLDER#SERIES
  }
  for (const auto& root : roots) {
    std::error_code ec;
    fs::path r = fs::weakly_canonical(root, ec);
    fs::path c = fs::weakly_canonical(requested.is_absolute() ? requested : r / requested, ec);
    if (inside(c, r)) throw VolumeError(requested, "no such file in the data directories");
  }
  throw VolumeError(requested, "path is outside the configured data directories");
}

}  // namespace peakcast
