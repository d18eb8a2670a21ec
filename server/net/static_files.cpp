#include "net/static_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>

namespace fs = std::filesystem;

namespace peakcast::net {

void StaticFiles::add_root(const fs::path& root, const std::string& url_prefix, bool (*accept)(const std::string&)) {
  std::error_code ec;
  const fs::path base = fs::weakly_canonical(root, ec);
  if (ec || !fs::is_directory(base, ec)) return;
  for (auto it = fs::recursive_directory_iterator(base, fs::directory_options::skip_permission_denied, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (files_.size() >= kMaxFiles) break;
    const std::string name = it->path().filename().string();
    if (!name.empty() && name[0] == '.') {  // hidden files and folders are not served
      if (it->is_directory(ec)) it.disable_recursion_pending();
      continue;
    }
    if (it->is_directory(ec) && name == "node_modules") {
      it.disable_recursion_pending();
      continue;
    }
    std::error_code e2;
    if (!it->is_regular_file(e2)) continue;
    const fs::path real = fs::canonical(it->path(), e2);  // a link must stay inside the root
    if (e2) continue;
    const fs::path rel = real.lexically_relative(base);
    if (rel.empty() || *rel.begin() == ".." || rel.is_absolute()) continue;
    const std::string url_rel = it->path().lexically_relative(base).generic_string();
    if (accept && !accept(url_rel)) continue;
    files_.emplace(url_prefix + url_rel, real);
  }
}

std::optional<fs::path> StaticFiles::find(const std::string& url_path) const {
  const auto it = files_.find(url_path == "/" || url_path.empty() ? "/index.html" : url_path);
  if (it == files_.end()) return std::nullopt;
  return it->second;
}

std::optional<std::string> StaticFiles::read(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > kMaxBytes) return std::nullopt;
  std::string body(size_t(st.st_size), '\0');
  size_t got = 0;
  while (got < body.size()) {
    const ssize_t n = ::read(fd, body.data() + got, body.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += size_t(n);
  }
  body.resize(got);
  return body;
}

const char* mime_type(const std::string& path) {
  auto ends = [&](const char* ext) { return path.size() >= std::strlen(ext) && path.ends_with(ext); };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js") || ends(".mjs")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".json")) return "application/json";
  if (ends(".svg")) return "image/svg+xml";
  if (ends(".png")) return "image/png";
  if (ends(".ico")) return "image/x-icon";
  if (ends(".md")) return "text/plain; charset=utf-8";  // the docs, read as text
  return "application/octet-stream";
}

}  // namespace peakcast::net
