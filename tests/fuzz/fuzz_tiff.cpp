// Any bytes as a multi-page TIFF read through OpenImageIO: loaded within a 4096-voxel limit or
// refused with a VolumeError, never a crash or a big allocation. Seeds: tests/fuzz/seeds/fuzz_tiff
// (small real stacks and broken ones).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path file = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_tiff_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d / "stack.tif";
  }();
  fuzz_load(file, data, size);
  return 0;
}
