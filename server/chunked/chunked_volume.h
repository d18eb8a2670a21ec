// Volumes kept as chunked multiresolution pyramids (docs/chunked-volumes.md): OME-Zarr (NGFF 0.4
// multiscales over zarr v2 arrays, or one bare zarr array) and Neuroglancer precomputed, as local
// directories. Opening reads metadata only; voxels are read a box at a time, chunk by chunk.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/volume.h"
#include "core/volume_io.h"

namespace peakcast::chunked {

// One resolution level: a box of voxels cut into chunks (x fastest, as Volume).
struct ChunkLevel {
  Dims dims{0, 0, 0};
  Dims chunk{0, 0, 0};
  glm::dvec3 spacing{1.0, 1.0, 1.0};
  glm::dvec3 origin{0.0, 0.0, 0.0};
  std::string name;  // the level's folder, relative to the root (for messages)
  Dims chunk_grid() const {
    return {(dims[0] + chunk[0] - 1) / chunk[0], (dims[1] + chunk[1] - 1) / chunk[1],
            (dims[2] + chunk[2] - 1) / chunk[2]};
  }
};

// Which 3D volume of a 4D or 5D array (OME-Zarr t, c; a precomputed volume's channel).
struct ChunkSelect {
  int64_t time = 0;
  int64_t channel = 0;
};

class ChunkedVolume {
 public:
  virtual ~ChunkedVolume() = default;
  const std::filesystem::path& root() const { return root_; }
  const char* format() const { return format_; }
  const std::vector<ChunkLevel>& levels() const { return levels_; }
  SourceType source() const { return source_; }
  bool big_endian() const { return big_endian_; }
  // The spacing's unit, an SI symbol ("nm"; core/length_unit.h); "": the metadata names none.
  const std::string& unit() const { return unit_; }
  // A time series: the time point read (ChunkSelect::time) and how many the array holds.
  int64_t time_point() const { return time_point_; }
  int64_t time_points() const { return time_points_; }
  // One voxel's bytes (file byte order) for a level's chunks that are not stored.
  const std::vector<uint8_t>& fill(int level) const { return fills_[size_t(level)]; }

  // The chunk at chunk index `c` of `level`, cut to the level's box: (chunk box ∩ dims) voxels, x
  // fastest, in the file's byte order. Nothing when the chunk is not stored (it reads as fill).
  // Throws VolumeError naming the chunk's file when it is there but wrong. Thread-safe.
  virtual std::optional<std::vector<uint8_t>> read_chunk(int level, const Dims& c) const = 0;
  // The bytes one chunk of `level` decodes to before it is cut to its box (a zarr chunk holds its
  // whole chunk shape, time and channel axes included): what a read charges per chunk in flight.
  virtual int64_t decoded_chunk_bytes(int level) const = 0;

 protected:
  std::filesystem::path root_;
  const char* format_ = "";
  std::vector<ChunkLevel> levels_;
  SourceType source_ = SourceType::U8;
  bool big_endian_ = false;
  std::string unit_;
  int64_t time_point_ = 0, time_points_ = 1;
  std::vector<std::vector<uint8_t>> fills_;  // per level
  // The level's folder listed once, on its first chunk (chunked/formats.h, FolderIndex): whether
  // a chunk may be stored there, without a stat per missing chunk. Thread-safe.
  bool may_hold(int level, const std::filesystem::path& folder, const std::string& rel) const;

 private:
  mutable std::mutex index_m_;
  mutable std::map<int, std::shared_ptr<const class FolderIndex>> index_;
};

// A directory that holds a chunked volume: .zattrs with "multiscales", a .zarray, or a
// Neuroglancer `info`.
bool is_chunked_volume(const std::filesystem::path& dir);

// Reads metadata only. Throws VolumeError naming the file and what is wrong or unsupported.
std::unique_ptr<ChunkedVolume> open_chunked(const std::filesystem::path& dir, const ChunkSelect& select = {});

// The box options.region (default: all) of `level`, read chunk by chunk on the machine's cores and
// finished as every reader finishes (byte order, signed shift, non-finite policy, statistics).
// A region read's volume carries source_dims and region_lo as other formats' do.
Volume read_level(const ChunkedVolume& volume, int level, const LoadOptions& options);

// The finest level from `from` on whose voxels (in memory) fit `budget_bytes`. Throws VolumeError
// when even the coarsest does not.
int finest_level_within(const ChunkedVolume& volume, int from, int64_t budget_bytes);
// A first look (serve --preview-voxels): the finest level from `from` on with at most `voxels`
// voxels (the coarsest when none has so few).
int finest_level_of_voxels(const ChunkedVolume& volume, int from, int64_t voxels);

// The largest size of one decoded chunk a reader accepts, and the most chunks one read visits
// (a level cut into chunks of a few voxels is refused rather than stat'ed chunk by chunk).
constexpr int64_t kMaxChunkBytes = int64_t(512) << 20;
constexpr int64_t kMaxChunksPerRead = int64_t(1) << 20;
// The largest edge of a level, in voxels (sizes and offsets then never overflow 64 bits).
constexpr int64_t kMaxLevelEdge = int64_t(1) << 40;

}  // namespace peakcast::chunked
