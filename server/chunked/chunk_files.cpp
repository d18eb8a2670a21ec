// What the chunked readers share: bounded file reads, metadata JSON, paths kept inside the
// volume's folder, overflow-checked sizes.
#include <cmath>
#include <cstring>
#include <fstream>

#include "chunked/formats.h"
#include "core/file_roots.h"

namespace fs = std::filesystem;

namespace peakcast::chunked {

std::optional<std::vector<uint8_t>> read_file_if_there(const fs::path& file, int64_t limit) {
  file_roots::check(file);  // a chunk or level linked out of the data directories is refused
  std::error_code ec;
  const bool there = fs::exists(file, ec);
  if (ec) throw VolumeError(file, "cannot be read: " + ec.message());  // not "missing": no fill value for it
  if (!there) return std::nullopt;
  if (!fs::is_regular_file(file, ec)) throw VolumeError(file, "not a regular file");
  const auto size = fs::file_size(file, ec);
  if (ec) throw VolumeError(file, "cannot read its size: " + ec.message());
  if (int64_t(size) > limit)
    throw VolumeError(file,
                      std::to_string(size) + " bytes is more than this chunk can hold (" + std::to_string(limit) + ")");
  std::vector<uint8_t> bytes(size);
  std::ifstream in(file, std::ios::binary);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size))) throw VolumeError(file, "cannot be read");
  return bytes;
}

FolderIndex::FolderIndex(const fs::path& dir) {
  std::error_code ec;
  // Links are followed (a chunk or folder linked out is then refused when read, not taken for
  // missing); the depth and entry caps end a loop.
  auto it = fs::recursive_directory_iterator(dir, fs::directory_options::follow_directory_symlink, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (names_.size() >= kMaxEntries || it.depth() > 6) return;  // not indexed
    names_.insert(it->path().lexically_relative(dir).generic_string());
  }
  indexed_ = !ec;
}

nlohmann::json read_json_file(const fs::path& file) {
  const auto bytes = read_file_if_there(file, 1 << 20);
  if (!bytes) throw VolumeError(file, "missing");
  nlohmann::json j = nlohmann::json::parse(bytes->begin(), bytes->end(), nullptr, false);
  if (j.is_discarded()) throw VolumeError(file, "not valid JSON");
  if (!j.is_object()) throw VolumeError(file, "must be a JSON object");
  return j;
}

fs::path inside(const fs::path& dir, const std::string& rel, const fs::path& meta) {
  const fs::path p(rel);
  bool ok =
      !rel.empty() && p.is_relative() && rel.find('\0') == std::string::npos && rel.find('\\') == std::string::npos;
  for (const auto& part : p)
    if (part.empty() || part == ".." || part == ".") ok = false;
  if (!ok) throw VolumeError(meta, "path '" + rel + "' must be a relative path inside the volume's folder");
  return dir / p;
}

void check_levels(const std::vector<ChunkLevel>& levels, const fs::path& file) {
  for (const ChunkLevel& L : levels) {
    int64_t count = 1;
    for (int a = 0; a < 3; ++a) {
      if (L.dims[a] < 1 || L.dims[a] > kMaxLevelEdge || L.chunk[a] < 1)
        throw VolumeError(file, "level " + L.name + ": sizes must be 1.." + std::to_string(kMaxLevelEdge));
      if (__builtin_mul_overflow(count, L.dims[a], &count))
        throw VolumeError(file, "level " + L.name + ": sizes overflow a 64-bit voxel count");
      if (!(L.spacing[a] > 0) || !std::isfinite(L.spacing[a]) || !std::isfinite(L.origin[a]))
        throw VolumeError(file, "level " + L.name + ": spacing must be finite and > 0, the origin finite");
    }
  }
}

int64_t checked_bytes(const std::vector<int64_t>& factors, const fs::path& file, const char* what) {
  int64_t n = 1;
  for (int64_t f : factors) {
    if (f <= 0) throw VolumeError(file, std::string(what) + ": every size must be >= 1");
    if (__builtin_mul_overflow(n, f, &n) || n > kMaxChunkBytes)
      throw VolumeError(file, std::string(what) + " is larger than the " + std::to_string(kMaxChunkBytes >> 20) +
                                  " MiB a chunk may hold");
  }
  return n;
}

std::vector<uint8_t> crop_block(const uint8_t* src, const Dims& full, const Dims& box, size_t bpv) {
  if (box == full) return std::vector<uint8_t>(src, src + size_t(full[0] * full[1] * full[2]) * bpv);
  std::vector<uint8_t> out(size_t(box[0] * box[1] * box[2]) * bpv);
  const size_t run = size_t(box[0]) * bpv;
  for (int64_t z = 0; z < box[2]; ++z)
    for (int64_t y = 0; y < box[1]; ++y)
      std::memcpy(out.data() + size_t(z * box[1] + y) * run, src + size_t((z * full[1] + y) * full[0]) * bpv, run);
  return out;
}

}  // namespace peakcast::chunked
