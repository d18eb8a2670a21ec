// Any bytes as the JSON sidecar of a raw volume (v.raw + v.raw.json): loaded within a 4096-voxel
// limit or refused with a VolumeError, never a crash or a big allocation.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_json_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    std::ofstream(d / "v.raw") << std::string(512, 'x');
    std::ofstream(d / "other.raw") << std::string(64, 'y');
    return d;
  }();
  fuzz_load(dir / "v.raw.json", data, size, dir / "v.raw");
  return 0;
}
