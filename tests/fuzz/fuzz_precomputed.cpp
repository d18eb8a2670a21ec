// Any bytes as a Neuroglancer precomputed image: the input is cut at "\n--\n" into `info` and the
// chunk 0-4_0-4_0-4 of scale "s". Loaded within a 4096-voxel limit or refused with a VolumeError,
// never a crash or a big allocation.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_load.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_precomputed_" + std::to_string(getpid()));
    std::filesystem::create_directories(d / "ng/s");
    return d;
  }();
  const std::string in(reinterpret_cast<const char*>(data), size);
  const size_t cut = in.find("\n--\n");
  const std::string info = in.substr(0, cut);
  const std::string chunk = cut == std::string::npos ? std::string() : in.substr(cut + 4);
  std::ofstream(dir / "ng/s/0-4_0-4_0-4", std::ios::binary).write(chunk.data(), std::streamsize(chunk.size()));
  fuzz_load(dir / "ng/info", reinterpret_cast<const uint8_t*>(info.data()), info.size(), dir / "ng");
  return 0;
}
