// The files the server hands out without a token: the browser client (--web-dir) and the docs its
// help links open (docs/ beside it). A fixed list, made when the server starts: every regular
// file under each root (links followed only where they stay inside the root), under the URL path
// it has there. A request is looked up in the list; a URL path is never joined to a root, so
// "//etc/passwd", "/docs//abs/path" or a device or FIFO is simply not there.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

namespace peakcast::net {

class StaticFiles {
 public:
  StaticFiles() = default;
  // `url_prefix` + each file's path relative to `root` ("/" + "src/main.js", "/docs/" + "rest.md");
  // `accept(relative path)` chooses which files are listed. A missing root lists nothing.
  void add_root(const std::filesystem::path& root, const std::string& url_prefix,
                bool (*accept)(const std::string& relative) = nullptr);
  // The file for a URL path ("/" is "/index.html"); nothing when the path is not in the list.
  std::optional<std::filesystem::path> find(const std::string& url_path) const;
  size_t size() const { return files_.size(); }

  // A listed file's bytes: opened without following a link and without blocking, and only while it
  // is still a regular file of at most kMaxBytes. Nothing otherwise.
  static std::optional<std::string> read(const std::filesystem::path& file);
  static constexpr int64_t kMaxBytes = int64_t(32) << 20;
  static constexpr size_t kMaxFiles = 10000;

 private:
  std::map<std::string, std::filesystem::path> files_;
};

const char* mime_type(const std::string& path);

}  // namespace peakcast::net
