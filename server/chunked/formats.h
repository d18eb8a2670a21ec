// The chunked formats' openers and what their readers share (chunked_volume.h is the interface).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include <nlohmann/json.hpp>

#include "chunked/chunked_volume.h"

namespace peakcast::chunked {

std::unique_ptr<ChunkedVolume> open_zarr(const std::filesystem::path& dir, const ChunkSelect& select);
std::unique_ptr<ChunkedVolume> open_precomputed(const std::filesystem::path& dir, const ChunkSelect& select);

// A file's bytes, or nothing when it does not exist; refused past `limit` bytes.
std::optional<std::vector<uint8_t>> read_file_if_there(const std::filesystem::path& file, int64_t limit);
// The files stored under a level's folder (relative paths, "/" between parts), listed once: a
// chunk that is not there is then known without a stat of its own, so a level of a million
// missing chunks costs one listing, not a million system calls. A folder of more than kMaxEntries
// entries (or deeper than 6) is not indexed: every chunk is then looked up on its own.
class FolderIndex {
 public:
  explicit FolderIndex(const std::filesystem::path& dir);
  // True when `rel` may be there (always, for a folder not indexed).
  bool may_hold(const std::string& rel) const { return !indexed_ || names_.count(rel) > 0; }
  static constexpr size_t kMaxEntries = size_t(1) << 22;

 private:
  bool indexed_ = false;
  std::unordered_set<std::string> names_;
};

// A metadata file (.zarray, .zattrs, info) parsed as JSON; refused when missing, over 1 MiB or
// not JSON.
nlohmann::json read_json_file(const std::filesystem::path& file);
// A path inside the volume's folder named by its metadata ("0", "8_8_8"): relative, without ".."
// or empty parts. Throws VolumeError naming `meta` otherwise.
std::filesystem::path inside(const std::filesystem::path& dir, const std::string& rel,
                             const std::filesystem::path& meta);
// Every level: an edge of 1..kMaxLevelEdge voxels, a voxel count that fits 64 bits, finite
// spacing > 0 and a finite origin. Throws VolumeError naming `file`.
void check_levels(const std::vector<ChunkLevel>& levels, const std::filesystem::path& file);
// a * b * ..., refused (VolumeError naming `file`) on overflow or past kMaxChunkBytes.
int64_t checked_bytes(const std::vector<int64_t>& factors, const std::filesystem::path& file, const char* what);
// Copies the box `box` (x, y, z sizes) out of a larger x-fastest block of `full` sizes, from its
// corner: rows of box[0] voxels.
std::vector<uint8_t> crop_block(const uint8_t* src, const Dims& full, const Dims& box, size_t bpv);

}  // namespace peakcast::chunked
