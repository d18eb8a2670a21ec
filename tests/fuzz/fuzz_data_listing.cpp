// Any bytes as the folder a client asks the data browser for (/api/files?dir=): listed or refused
// with a VolumeError, never a crash, never a name from outside the data directory (the tree holds
// a link out, a name that is not UTF-8 and a FIFO), and the listing serialises as JSON.
#include <sys/stat.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "core/utf8.h"
#include "core/volume_io.h"
#include "session/data_listing.h"

namespace fs = std::filesystem;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const fs::path root = [] {
    const fs::path d = fs::temp_directory_path() / ("peakcast_fuzz_listing_" + std::to_string(getpid()));
    fs::create_directories(d / "data/sub/v.zarr");
    fs::create_directories(d / "outside");
    std::ofstream(d / "outside/secret.nrrd") << "NRRD0004\n";
    std::ofstream(d / "data/sub/a.nrrd") << "NRRD0004\n";
    std::ofstream(d / "data/sub/v.zarr/.zarray") << "{}";
    std::ofstream(d / "data/bad\xff.nhdr") << "NRRD0004\n";
    std::error_code ec;
    fs::create_directory_symlink(d / "outside", d / "data/out", ec);
    ::mkfifo((d / "data/fifo.nrrd").c_str(), 0600);
    return d / "data";
  }();
  const std::string dir(reinterpret_cast<const char*>(data), size);
  try {
    const auto list = peakcast::list_data_dir({root}, dir);
    const std::string text = peakcast::json_text(list);
    if (!peakcast::valid_utf8(text)) std::abort();
    for (const auto& e : list["entries"])  // the request is echoed in "dir"; the entries are the server's
      if (peakcast::json_text(e).find("secret") != std::string::npos) std::abort();
  } catch (const peakcast::VolumeError&) {
  }
  return 0;
}
