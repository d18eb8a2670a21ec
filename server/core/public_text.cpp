#include "core/public_text.h"

#include <filesystem>
#include <set>

#include "core/utf8.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

// The names in "/" (read once): a path starting with one of them is a server path.
const std::set<std::string>& root_names() {
  static const std::set<std::string> names = [] {
    std::set<std::string> out;
    std::error_code ec;
    for (auto it = fs::directory_iterator("/", ec); !ec && it != fs::directory_iterator(); it.increment(ec))
      out.insert(it->path().filename().string());
    return out;
  }();
  return names;
}

bool ends_path(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\'' || c == '"' || c == ',' || c == ')' || c == ']';
}
bool starts_token(char c) { return ends_path(c) || c == '(' || c == '[' || c == '=' || c == ':'; }

}  // namespace

std::string public_text(std::string_view message, size_t max_bytes) {
  const std::string s = clean_utf8(message);
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    if (s[i] == '/' && (i == 0 || starts_token(s[i - 1]))) {
      size_t end = i;
      while (end < s.size() && !ends_path(s[end]) && !(s[end] == ':' && (end + 1 == s.size() || s[end + 1] == ' ')))
        ++end;
      const std::string_view path(s.data() + i, end - i);
      size_t first_end = path.find('/', 1);
      const std::string first(
          path.substr(1, first_end == std::string_view::npos ? std::string_view::npos : first_end - 1));
      if (!first.empty() && root_names().count(first)) {
        std::string_view last = path;
        while (!last.empty() && last.back() == '/') last.remove_suffix(1);
        last = last.substr(last.rfind('/') + 1);
        out += last.empty() ? std::string_view("(server path)") : last;
        i = end;
        continue;
      }
    }
    out += s[i++];
  }
  return clean_utf8(out, max_bytes);
}

}  // namespace peakcast
