// Helpers shared by the chunked-volume tests (chunked_test.cpp, precomputed_test.cpp).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/volume_io.h"
#include "unit/test_util.h"

namespace peakcast::test {

inline void write_json(const std::filesystem::path& p, const nlohmann::json& j) { write_file(p, j.dump()); }

inline std::string bytes_str(const std::vector<uint8_t>& b) { return std::string(b.begin(), b.end()); }

// The refusal's message, or "" when it loads.
inline std::string refusal(const std::filesystem::path& p, LoadOptions o = {}) {
  try {
    load_volume(p, o);
  } catch (const VolumeError& e) {
    return e.what();
  }
  return "";
}

}  // namespace peakcast::test
