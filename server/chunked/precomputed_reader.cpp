// Neuroglancer precomputed images: `info` (type image, data_type, num_channels, scales with key,
// size, resolution in nm, voxel_offset, chunk_sizes), unsharded chunks in "raw" encoding, each
// file `key/x0-x1_y0-y1_z0-z1` (plain, gzip-compressed, or with a .gz suffix).
#include <cmath>

#include "chunked/chunk_codec.h"
#include "chunked/formats.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace peakcast::chunked {
namespace {

std::array<double, 3> three(const json& v, const std::string& what, const fs::path& file) {
  std::array<double, 3> out{};
  if (!v.is_array() || v.size() != 3) throw VolumeError(file, what + " must be 3 numbers");
  for (size_t i = 0; i < 3; ++i) {
    if (!v[i].is_number()) throw VolumeError(file, what + " must be 3 numbers");
    out[i] = v[i].get<double>();
  }
  return out;
}

std::array<double, 3> triple(const json& s, const char* key, const fs::path& file, bool required) {
  if (s.contains(key)) return three(s[key], key, file);
  if (required) throw VolumeError(file, std::string("every scale needs \"") + key + "\"");
  return {0, 0, 0};
}

class PrecomputedVolume : public ChunkedVolume {
 public:
  PrecomputedVolume(const fs::path& dir, const ChunkSelect& select) : channel_(select.channel) {
    root_ = dir;
    format_ = "Neuroglancer precomputed";
    const fs::path file = dir / "info";
    const json info = read_json_file(file);
    if (info.contains("type") && info["type"] != "image")
      throw VolumeError(file, "type " + info["type"].dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) +
                                  " is not an image (segmentations are not volumes to render)");
    const std::string dt =
        info.contains("data_type") && info["data_type"].is_string() ? info["data_type"].get<std::string>() : "";
    static const std::pair<const char*, SourceType> kinds[] = {{"uint8", SourceType::U8},
                                                               {"int8", SourceType::I8},
                                                               {"uint16", SourceType::U16},
                                                               {"int16", SourceType::I16},
                                                               {"float32", SourceType::F32}};
    bool known = false;
    for (const auto& [name, type] : kinds)
      if (dt == name) source_ = type, known = true;
    if (!known)
      throw VolumeError(file, "data_type '" + dt + "' is not supported (uint8, int8, uint16, int16, float32)");
    const json nc = info.value("num_channels", json(1));
    if (!nc.is_number_integer() || nc.get<int64_t>() < 1 || nc.get<int64_t>() > 4096)
      throw VolumeError(file, "num_channels must be an integer from 1 to 4096");
    channels_ = nc.get<int64_t>();
    if (select.time != 0) throw VolumeError(file, "a precomputed volume has no time axis");
    if (channel_ < 0 || channel_ >= channels_)
      throw VolumeError(file,
                        "channel " + std::to_string(channel_) + " is outside 0.." + std::to_string(channels_ - 1));
    if (!info.contains("scales") || !info["scales"].is_array() || info["scales"].empty())
      throw VolumeError(file, "scales must be a non-empty list");
    for (const json& s : info["scales"]) {
      if (!s.is_object() || !s.contains("key") || !s["key"].is_string())
        throw VolumeError(file, "every scale needs a \"key\"");
      if (s.contains("sharding") && !s["sharding"].is_null())
        throw VolumeError(file, "sharded scales are not supported (write the volume unsharded)");
      const std::string enc = s.value("encoding", std::string("raw"));
      if (enc != "raw")
        throw VolumeError(file, "encoding '" + enc + "' is not supported (raw, optionally gzip-compressed)");
      const auto size = triple(s, "size", file, true), res = triple(s, "resolution", file, true);
      const auto off = triple(s, "voxel_offset", file, false);
      if (!s.contains("chunk_sizes") || !s["chunk_sizes"].is_array() || s["chunk_sizes"].empty())
        throw VolumeError(file, "every scale needs chunk_sizes");
      const auto chunk = three(s["chunk_sizes"][0], "chunk_sizes[0]", file);
      ChunkLevel L;
      L.name = s["key"];
      inside(dir, L.name, file);
      Dims offset{};
      for (int a = 0; a < 3; ++a) {
        auto whole = [&](double v, const char* what, bool positive) {
          if (!(std::abs(v) <= 1e15) || v != std::floor(v) || (positive && v < 1))
            throw VolumeError(file, std::string(what) + " must be whole numbers" + (positive ? " >= 1" : ""));
          return int64_t(v);
        };
        L.dims[a] = whole(size[size_t(a)], "size", true);
        L.chunk[a] = whole(chunk[size_t(a)], "chunk_sizes", true);
        offset[a] = whole(off[size_t(a)], "voxel_offset", false);
        if (!(res[size_t(a)] > 0) || !std::isfinite(res[size_t(a)]))
          throw VolumeError(file, "resolution must be finite and > 0");
        L.spacing[a] = res[size_t(a)];
        L.origin[a] = (double(offset[a]) + 0.5) * res[size_t(a)];  // voxel i spans [i, i+1): its centre
      }
      checked_bytes({L.chunk[0], L.chunk[1], L.chunk[2], channels_, int64_t(source_bytes(source_))}, file, "a chunk");
      levels_.push_back(L);
      unit_ = "nm";  // the format's resolution is in nanometres
      offsets_.push_back(offset);
      fills_.push_back(std::vector<uint8_t>(source_bytes(source_), 0));  // Neuroglancer shows a missing chunk as 0
    }
  }

  int64_t decoded_chunk_bytes(int level) const override {
    const ChunkLevel& L = levels_[size_t(level)];
    return L.chunk[0] * L.chunk[1] * L.chunk[2] * int64_t(source_bytes(source_)) * channels_;
  }

  std::optional<std::vector<uint8_t>> read_chunk(int level, const Dims& c) const override {
    const ChunkLevel& L = levels_[size_t(level)];
    const Dims& off = offsets_[size_t(level)];
    Dims box{};
    std::string name;
    for (int a = 0; a < 3; ++a) {
      const int64_t lo = c[a] * L.chunk[a], hi = std::min(lo + L.chunk[a], L.dims[a]);
      box[a] = hi - lo;
      name += (a ? "_" : "") + std::to_string(off[a] + lo) + "-" + std::to_string(off[a] + hi);
    }
    const size_t bpv = source_bytes(source_);
    const size_t one = size_t(box[0] * box[1] * box[2]) * bpv;
    const size_t expected = one * size_t(channels_);
    const int64_t limit = int64_t(expected) + (int64_t(expected) >> 3) + (int64_t(1) << 20);
    if (!may_hold(level, root_ / L.name, name) && !may_hold(level, root_ / L.name, name + ".gz"))
      return std::nullopt;  // not stored: zeros
    fs::path file = root_ / L.name / name;
    auto raw = read_file_if_there(file, limit);
    if (!raw) {
      file += ".gz";
      raw = read_file_if_there(file, limit);
    }
    if (!raw) return std::nullopt;
    // Gzip when the name says so or the bytes start as gzip does and inflate to the chunk; a raw
    // chunk whose first voxels happen to read 1f 8b is raw (a gzip stream may also happen to be
    // exactly the raw chunk's size: that alone tells nothing).
    std::vector<uint8_t> all;
    if (file.extension() == ".gz") {
      all = decode_chunk({Compressor::Gzip}, *raw, expected, file);
    } else if (looks_gzip(*raw)) {
      try {
        all = decode_chunk({Compressor::Gzip}, *raw, expected, file);
      } catch (const VolumeError&) {
        if (raw->size() != expected) throw;
        all = std::move(*raw);
      }
    } else {
      all = decode_chunk({Compressor::None}, *raw, expected, file);
    }
    if (channels_ == 1) return all;
    const auto* first = all.data() + size_t(channel_) * one;  // channels outermost: [c][z][y][x]
    return std::vector<uint8_t>(first, first + one);
  }

 private:
  int64_t channel_ = 0, channels_ = 1;
  std::vector<Dims> offsets_;
};

}  // namespace

std::unique_ptr<ChunkedVolume> open_precomputed(const fs::path& dir, const ChunkSelect& select) {
  return std::make_unique<PrecomputedVolume>(dir, select);
}

}  // namespace peakcast::chunked
