// Any bytes as a MetaImage header: .mhd naming a detached data file, or .mha with LOCAL data
// (the first byte picks). Loaded within a 4096-voxel limit or refused with a VolumeError.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/volume_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_mhd_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    std::ofstream(d / "data.raw") << std::string(512, 'x');  // a detached data file headers may name
    return d;
  }();
  const auto file = dir / (data[0] & 1 ? "h.mha" : "h.mhd");
  {
    std::ofstream out(file, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
  }
  peakcast::LoadOptions opt;
  opt.max_voxels = 4096;
  try {
    peakcast::load_volume(file, opt);
  } catch (const peakcast::VolumeError&) {
  }
  return 0;
}
