// Any bytes as an OME-Zarr image: the input is cut at "\n--\n" into .zattrs, level 0's .zarray and
// one chunk (stored under both key separators). Loaded within a 4096-voxel limit or refused with
// a VolumeError, never a crash or a big allocation.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "fuzz_load.h"

namespace {

void put(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_zarr_" + std::to_string(getpid()));
    std::filesystem::create_directories(d / "v.zarr/0/0/0");
    return d;
  }();
  const std::string in(reinterpret_cast<const char*>(data), size);
  std::string part[3];
  size_t at = 0;
  for (int i = 0; i < 3; ++i) {
    const size_t cut = i < 2 ? in.find("\n--\n", at) : std::string::npos;
    part[i] = in.substr(at, cut == std::string::npos ? std::string::npos : cut - at);
    at = cut == std::string::npos ? in.size() : cut + 4;
  }
  const auto root = dir / "v.zarr";
  put(root / ".zattrs", part[0]);
  put(root / "0/.zarray", part[1]);
  put(root / "0/0/0/0", part[2]);
  put(root / "0/0.0.0", part[2]);
  fuzz_load(root / ".zattrs", reinterpret_cast<const uint8_t*>(part[0].data()), part[0].size(), root);
  return 0;
}
