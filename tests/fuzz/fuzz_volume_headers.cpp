// Any bytes as a NRRD, MetaImage or raw+JSON header (the first byte picks the format): loaded
// within a 4096-voxel limit or refused with a VolumeError, never a crash or a big allocation.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    std::ofstream(d / "data.raw") << std::string(512, 'x');  // a detached data file headers may name
    return d;
  }();
  static const char* ext[] = {".nrrd", ".nhdr", ".mhd", ".mha", ".json"};
  fuzz_load(dir / (std::string("h") + ext[data[0] % 5]), data + 1, size - 1);
  return 0;
}
