#include "chunked/zarr_writer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include "core/length_unit.h"
#include "core/parallel.h"
#include "core/volume_io.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace peakcast::chunked {
namespace {

// One level's voxels in the volume's storage type (signed types shifted, as Volume keeps them).
struct Level {
  Dims dims{};
  std::vector<uint8_t> bytes;
};

template <typename T>
void halve(const Dims& in_dims, const uint8_t* in, Level& out) {
  for (int a = 0; a < 3; ++a) out.dims[a] = (in_dims[a] + 1) / 2;
  out.bytes.assign(size_t(out.dims[0] * out.dims[1] * out.dims[2]) * sizeof(T), 0);
  const T* src = reinterpret_cast<const T*>(in);
  T* dst = reinterpret_cast<T*>(out.bytes.data());
  const Dims d = in_dims, o = out.dims;
  parallel_chunks(size_t(o[2]), [&](size_t z0, size_t z1, int) {
    for (int64_t z = int64_t(z0); z < int64_t(z1); ++z)
      for (int64_t y = 0; y < o[1]; ++y)
        for (int64_t x = 0; x < o[0]; ++x) {
          double sum = 0.0;
          int n = 0;
          for (int64_t k = 2 * z; k < std::min(2 * z + 2, d[2]); ++k)
            for (int64_t j = 2 * y; j < std::min(2 * y + 2, d[1]); ++j)
              for (int64_t i = 2 * x; i < std::min(2 * x + 2, d[0]); ++i, ++n)
                sum += double(src[(k * d[1] + j) * d[0] + i]);
          const double mean = sum / n;
          dst[(z * o[1] + y) * o[0] + x] = std::is_floating_point_v<T> ? T(mean) : T(std::lround(mean));
        }
  });
}

const char* dtype_of(SourceType t) {
  switch (t) {
    case SourceType::U8: return "|u1";
    case SourceType::I8: return "|i1";
    case SourceType::U16: return "<u2";
    case SourceType::I16: return "<i2";
    case SourceType::F32: return "<f4";
  }
  return "";
}

void write_file(const fs::path& file, const void* data, size_t n) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(static_cast<const char*>(data), std::streamsize(n));
  out.close();
  if (!out) throw VolumeError(file, "write failed");
}

void write_json(const fs::path& file, const json& j) {
  const std::string s = j.dump(2) + "\n";
  write_file(file, s.data(), s.size());
}

// The multiscales block of the levels written so far (rewritten as each level completes, so the
// folder being written reads as an OME-Zarr of those levels: zarr_convert reads the level below
// from it). A series (time_points > 1) has a leading t axis.
void write_attrs(const fs::path& dir, const VolumeHeader& h, const std::string& name, const json& datasets) {
  json axes = json::array();
  if (h.time_points > 1) axes.push_back({{"name", "t"}, {"type", "time"}});
  for (const char* n : {"z", "y", "x"}) {
    json ax = {{"name", n}, {"type", "space"}};
    if (const std::string u = ngff_unit_name(h.unit); !u.empty()) ax["unit"] = u;
    axes.push_back(ax);
  }
  write_json(dir / ".zattrs", {{"multiscales",
                                {{{"version", "0.4"},
                                  {"name", name},
                                  {"axes", axes},
                                  {"datasets", datasets},
                                  {"type", "mean"},
                                  {"metadata", {{"method", "2x2x2 mean, sizes rounded up"}}}}}}});
}

// Level k's dataset entry: its scale and the translation of a 2^k block's mean.
json dataset_entry(const VolumeHeader& h, int k) {
  const double f = std::ldexp(1.0, k);  // this level's voxel edge in level-0 voxels
  json scale = json::array(), shift = json::array();
  if (h.time_points > 1) {
    scale.push_back(1.0);
    shift.push_back(0.0);
  }
  for (int a = 2; a >= 0; --a) {
    scale.push_back(h.spacing[a] * f);
    shift.push_back(h.origin[a] + 0.5 * (f - 1.0) * h.spacing[a]);  // the mean's centre
  }
  return {{"path", std::to_string(k)},
          {"coordinateTransformations",
           {{{"type", "scale"}, {"scale", scale}}, {{"type", "translation"}, {"translation", shift}}}}};
}

// One level of `dims` in dir: its .zarray and every chunk (of every time point) from `fill`.
void write_level(const fs::path& dir, const VolumeHeader& h, int k, const Dims& dims, const ZarrWriteOptions& options,
                 const ChunkFill& fill, std::atomic<int64_t>& chunks, std::atomic<int64_t>& bytes) {
  const size_t bpv = source_bytes(h.source);
  const int64_t times = std::max<int64_t>(h.time_points, 1);
  const bool series = times > 1;
  fs::create_directories(dir);
  Dims e{};  // the chunk edge, no larger than the level (a thin slab gets thin chunks)
  for (int a = 0; a < 3; ++a) e[a] = std::min(options.chunk, dims[a]);
  json shape = {dims[2], dims[1], dims[0]}, chunk = {e[2], e[1], e[0]};
  if (series) {
    shape.insert(shape.begin(), times);
    chunk.insert(chunk.begin(), 1);
  }
  write_json(dir / ".zarray", {{"zarr_format", 2},
                               {"shape", shape},
                               {"chunks", chunk},
                               {"dtype", dtype_of(h.source)},
                               {"compressor", compressor_json(options.compressor)},
                               {"fill_value", 0},
                               {"order", "C"},
                               {"filters", nullptr},
                               {"dimension_separator", "/"}});
  const Dims grid{(dims[0] + e[0] - 1) / e[0], (dims[1] + e[1] - 1) / e[1], (dims[2] + e[2] - 1) / e[2]};
  auto time_dir = [&](int64_t t) { return series ? dir / std::to_string(t) : dir; };
  for (int64_t t = 0; t < times; ++t)
    for (int64_t z = 0; z < grid[2]; ++z)
      for (int64_t y = 0; y < grid[1]; ++y) fs::create_directories(time_dir(t) / std::to_string(z) / std::to_string(y));
  const size_t cells = size_t(grid[0] * grid[1] * grid[2]);
  parallel_for(cells * size_t(times), [&](size_t n) {  // time point by time point, z slowest
    const int64_t t = int64_t(n / cells), i = int64_t(n % cells);
    const Dims c{i % grid[0], i / grid[0] % grid[1], i / (grid[0] * grid[1])};
    Dims lo{}, box{};
    for (int a = 0; a < 3; ++a) {
      lo[a] = c[a] * e[a];
      box[a] = std::min(e[a], dims[a] - lo[a]);
    }
    std::vector<uint8_t> part(size_t(box[0] * box[1] * box[2]) * bpv);
    fill(k, t, lo, box, part.data());
    std::vector<uint8_t> whole(size_t(e[0] * e[1] * e[2]) * bpv, 0);  // zarr stores full chunks: 0-padded
    for (int64_t z = 0; z < box[2]; ++z)
      for (int64_t y = 0; y < box[1]; ++y)
        std::memcpy(whole.data() + size_t((z * e[1] + y) * e[0]) * bpv,
                    part.data() + size_t((z * box[1] + y) * box[0]) * bpv, size_t(box[0]) * bpv);
    const auto packed = encode_chunk(options.compressor, whole.data(), whole.size(), bpv);
    write_file(time_dir(t) / std::to_string(c[2]) / std::to_string(c[1]) / std::to_string(c[0]), packed.data(),
               packed.size());
    ++chunks;
    bytes += int64_t(packed.size());
  });
}

ZarrWriteReport write_levels(const fs::path& out, const fs::path& tmp, const VolumeHeader& h, int levels,
                             const std::string& name, const ZarrWriteOptions& options, const ChunkFill& fill) {
  std::error_code ec;
  ZarrWriteReport report;
  report.levels = levels;
  json datasets = json::array();
  std::atomic<int64_t> chunks{0}, bytes{0};
  write_json(tmp / ".zgroup", {{"zarr_format", 2}});
  Dims dims = h.dims;
  for (int k = 0; k < levels; ++k, dims = Dims{(dims[0] + 1) / 2, (dims[1] + 1) / 2, (dims[2] + 1) / 2}) {
    write_level(tmp / std::to_string(k), h, k, dims, options, fill, chunks, bytes);
    datasets.push_back(dataset_entry(h, k));
    write_attrs(tmp, h, name, datasets);
  }
  fs::rename(tmp, out, ec);
  if (ec) throw VolumeError(out, "cannot be put in place: " + ec.message());
  report.chunks = chunks;
  report.bytes = bytes;
  return report;
}

}  // namespace

void unshift_voxels(uint8_t* p, size_t n, SourceType source) {
  if (source == SourceType::I8)
    for (size_t i = 0; i < n; ++i) p[i] ^= 0x80;
  if (source == SourceType::I16)
    for (size_t i = 0; i < n; ++i) reinterpret_cast<uint16_t*>(p)[i] ^= 0x8000;
}

std::vector<uint8_t> halve_voxels(VoxelType type, const Dims& in_dims, const uint8_t* in, Dims& out_dims) {
  Level next;
  switch (type) {
    case VoxelType::U8: halve<uint8_t>(in_dims, in, next); break;
    case VoxelType::U16: halve<uint16_t>(in_dims, in, next); break;
    case VoxelType::F32: halve<float>(in_dims, in, next); break;
  }
  out_dims = next.dims;
  return std::move(next.bytes);
}

fs::path partial_path(const fs::path& out) { return out.string() + ".partial-" + std::to_string(::getpid()); }

int pyramid_levels(const Dims& dims, int64_t chunk) {
  int n = 1;
  for (Dims d = dims; std::max({d[0], d[1], d[2]}) > chunk; ++n)
    for (auto& x : d) x = (x + 1) / 2;
  return n;
}

ZarrWriteReport write_ome_zarr_levels(const fs::path& out, const VolumeHeader& h, int levels, const std::string& name,
                                      const ZarrWriteOptions& options, const ChunkFill& fill) {
  if (options.chunk < 1 || options.chunk > 512) throw std::invalid_argument("chunk edge must be 1..512 voxels");
  if (levels < 1) throw std::invalid_argument("a pyramid has at least one level");
  std::error_code ec;
  if (fs::exists(out, ec)) throw VolumeError(out, "already exists (remove it first)");
  // Written beside OUT under a name of this process's, renamed when whole.
  const fs::path tmp = partial_path(out);
  fs::remove_all(tmp, ec);
  if (!fs::create_directories(tmp, ec)) throw VolumeError(tmp, "cannot be created: " + ec.message());
  try {
    return write_levels(out, tmp, h, levels, name, options, fill);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(tmp, ec);
    throw VolumeError(out, e.what());
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

ZarrWriteReport write_ome_zarr(const Volume& volume, const fs::path& out, const ZarrWriteOptions& options) {
  if (options.chunk < 1 || options.chunk > 512) throw std::invalid_argument("chunk edge must be 1..512 voxels");
  if (!volume.has_voxels()) throw std::invalid_argument("the volume has no voxels here");
  std::error_code ec;
  if (fs::exists(out, ec)) throw VolumeError(out, "already exists (remove it first)");
  std::vector<Level> levels(1);
  levels[0].dims = volume.dims();
  levels[0].bytes.assign(volume.data(), volume.data() + volume.byte_size());
  const int n = options.pyramid ? pyramid_levels(volume.dims(), options.chunk) : 1;
  while (int(levels.size()) < n) {
    Level next;
    next.bytes = halve_voxels(volume.type(), levels.back().dims, levels.back().bytes.data(), next.dims);
    levels.push_back(std::move(next));
  }
  VolumeHeader h;
  h.dims = volume.dims();
  h.spacing = volume.spacing;
  h.origin = volume.origin;
  h.unit = volume.unit;
  h.source = volume.source_type();
  const size_t bpv = source_bytes(h.source);
  return write_ome_zarr_levels(
      out, h, n, volume.name, options, [&](int k, int64_t, const Dims& lo, const Dims& box, uint8_t* dst) {
        const Level& L = levels[size_t(k)];
        for (int64_t z = 0; z < box[2]; ++z)
          for (int64_t y = 0; y < box[1]; ++y) {
            uint8_t* row = dst + size_t((z * box[1] + y) * box[0]) * bpv;
            std::memcpy(row, L.bytes.data() + size_t(((lo[2] + z) * L.dims[1] + lo[1] + y) * L.dims[0] + lo[0]) * bpv,
                        size_t(box[0]) * bpv);
            unshift_voxels(row, size_t(box[0]), h.source);
          }
      });
}

}  // namespace peakcast::chunked
