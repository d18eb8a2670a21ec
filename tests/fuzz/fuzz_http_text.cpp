// Any bytes as what a request says: its target (path, query, token, an upload's raw header), its
// Host header and the static file it asks for. Parsed or refused, never a crash; a token compare
// agrees with ==; a Host that is allowed has a name.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "net/http_text.h"
#include "net/static_files.h"

namespace fs = std::filesystem;
using namespace peakcast::net;

namespace {

// A tiny client folder, listed once: the lookup may only ever answer one of its files.
const StaticFiles& statics() {
  static const StaticFiles files = [] {
    const fs::path d = fs::temp_directory_path() / ("peakcast_fuzz_http_" + std::to_string(getpid()));
    fs::create_directories(d / "web/src");
    fs::create_directories(d / "docs");
    std::ofstream(d / "web/index.html") << "<html>";
    std::ofstream(d / "web/src/main.js") << "//";
    std::ofstream(d / "docs/rest.md") << "# REST";
    StaticFiles f;
    f.add_root(d / "web", "/");
    f.add_root(d / "docs", "/docs/", [](const std::string& rel) { return rel.ends_with(".md"); });
    return f;
  }();
  return files;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string in(reinterpret_cast<const char*>(data), size);
  const auto nl = in.find('\n');
  const std::string target = in.substr(0, nl), header = nl == std::string::npos ? "" : in.substr(nl + 1);
  const std::string path = path_of(target);
  (void)url_decode(path);
  (void)query_param(target, "dir");
  (void)token_from(header, target);
  if (auto raw = raw_header_from_query(target))
    (void)raw->dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (tokens_equal(target, header) != (target == header)) std::abort();
  const std::string name = host_name(header);
  for (const char* bind : {"127.0.0.1", "0.0.0.0"}) {
    const HostCheck check(bind, {"viewer.example.org"});
    if (check.allowed(header) && !header.empty() && name.empty()) std::abort();  // allowed, yet no name
  }
  if (auto file = statics().find(path)) {
    const std::string f = file->string();
    if (f.find("peakcast_fuzz_http_") == std::string::npos) std::abort();  // only a listed file
    (void)StaticFiles::read(*file);
  }
  return 0;
}
