// Any bytes as a MetaImage header: .mhd naming a detached data file, or .mha with LOCAL data
// (the first byte picks). Loaded within a 4096-voxel limit or refused with a VolumeError.
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
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_mhd_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    std::ofstream(d / "data.raw") << std::string(512, 'x');  // a detached data file headers may name
    return d;
  }();
  fuzz_load(dir / (data[0] & 1 ? "h.mha" : "h.mhd"), data + 1, size - 1);
  return 0;
}
