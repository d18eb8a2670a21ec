// Shared by the volume-file fuzz targets: write the input as a file and load it within a
// 4096-voxel limit. A refusal (VolumeError, std::invalid_argument) is the expected outcome for
// most inputs; anything else (a crash, a sanitizer report, a big allocation) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/volume_io.h"

inline void fuzz_load(const std::filesystem::path& write_to, const uint8_t* data, size_t size,
                      const std::filesystem::path& load = {}) {
  {
    std::ofstream out(write_to, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  peakcast::LoadOptions opt;
  opt.max_voxels = 4096;
  try {
    peakcast::load_volume(load.empty() ? write_to : load, opt);
  } catch (const peakcast::VolumeError&) {
  } catch (const std::invalid_argument&) {
  }
}
