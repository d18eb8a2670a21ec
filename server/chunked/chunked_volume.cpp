#include "chunked/chunked_volume.h"

#include <algorithm>
#include <cstring>
#include <nlohmann/json.hpp>

#include "chunked/formats.h"
#include "core/parallel.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::chunked {

bool is_chunked_volume(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return false;
  return fs::is_regular_file(dir / ".zattrs", ec) || fs::is_regular_file(dir / ".zarray", ec) ||
         fs::is_regular_file(dir / "info", ec);
}

std::unique_ptr<ChunkedVolume> open_chunked(const fs::path& dir, const ChunkSelect& select) {
  std::error_code ec;
  std::unique_ptr<ChunkedVolume> v;
  try {  // a metadata value of the wrong JSON type is a refusal like any other
    if (fs::is_regular_file(dir / "info", ec) && !fs::exists(dir / ".zattrs", ec) && !fs::exists(dir / ".zarray", ec))
      v = open_precomputed(dir, select);
    else if (fs::is_regular_file(dir / ".zattrs", ec) || fs::is_regular_file(dir / ".zarray", ec))
      v = open_zarr(dir, select);
    else
      throw VolumeError(dir, "not a chunked volume (no .zattrs, .zarray or Neuroglancer info)");
  } catch (const nlohmann::json::exception& e) {
    throw VolumeError(dir, std::string("metadata: ") + e.what());
  }
  check_levels(v->levels(), dir);
  return v;
}

namespace {

// Copies the chunk box `cb` (voxels in `bytes`, or the fill value) into the region box of `dst`.
void place_chunk(const std::vector<uint8_t>* bytes, const std::vector<uint8_t>& fill, const Dims& clo, const Dims& chi,
                 const Dims& rlo, const Dims& rhi, size_t bpv, uint8_t* dst) {
  Dims a{}, b{};
  for (int i = 0; i < 3; ++i) {
    a[i] = std::max(clo[i], rlo[i]);
    b[i] = std::min(chi[i], rhi[i]);
  }
  const int64_t cx = chi[0] - clo[0], cy = chi[1] - clo[1];
  const int64_t rx = rhi[0] - rlo[0], ry = rhi[1] - rlo[1];
  const size_t run = size_t(b[0] - a[0]) * bpv;
  for (int64_t z = a[2]; z < b[2]; ++z)
    for (int64_t y = a[1]; y < b[1]; ++y) {
      uint8_t* d = dst + ((size_t((z - rlo[2]) * ry + (y - rlo[1])) * rx + size_t(a[0] - rlo[0])) * bpv);
      if (bytes) {
        const size_t s = (size_t((z - clo[2]) * cy + (y - clo[1])) * cx + size_t(a[0] - clo[0])) * bpv;
        std::memcpy(d, bytes->data() + s, run);
      } else {
        for (size_t o = 0; o < run; o += bpv) std::memcpy(d + o, fill.data(), bpv);
      }
    }
}

// How many chunks may be decoded at once within options.decode_budget_bytes beside the voxels
// (all cores when there is no budget). Refused before any chunk is read when not even one fits.
int decoders_within(const ChunkedVolume& cv, int level, const VolumeHeader& h, double chunks,
                    const LoadOptions& options) {
  const int most = int(std::min<double>(hardware_threads(), std::max(chunks, 1.0)));
  if (options.decode_budget_bytes <= 0) return most;
  const int64_t one = cv.decoded_chunk_bytes(level);
  const int64_t voxels = h.voxel_count() * int64_t(voxel_bytes(storage_type(h.source)));
  const int64_t left = options.decode_budget_bytes - voxels;
  if (one <= 0 || left < one)
    throw VolumeError(cv.root(), "level " + cv.levels()[size_t(level)].name + ": one chunk decodes to " +
                                     std::to_string(one >> 20) + " MiB, more than the memory budget of " +
                                     std::to_string(options.decode_budget_bytes >> 20) + " MiB leaves beside the " +
                                     std::to_string(voxels >> 20) + " MiB of voxels");
  return int(std::clamp<int64_t>(left / one, 1, most));
}

}  // namespace

bool ChunkedVolume::may_hold(int level, const fs::path& folder, const std::string& rel) const {
  std::shared_ptr<const FolderIndex> index;
  {
    std::lock_guard lock(index_m_);  // the first chunk of a level lists its folder; the others wait
    auto& slot = index_[level];
    if (!slot) slot = std::make_shared<const FolderIndex>(folder);
    index = slot;
  }
  return index->may_hold(rel);
}

int finest_level_within(const ChunkedVolume& cv, int from, int64_t budget_bytes) {
  const int64_t bpv = int64_t(voxel_bytes(storage_type(cv.source())));
  for (int k = std::max(from, 0); k < int(cv.levels().size()); ++k) {
    const Dims& d = cv.levels()[size_t(k)].dims;
    if (double(d[0]) * double(d[1]) * double(d[2]) * double(bpv) <= double(budget_bytes)) return k;
  }
  const Dims& d = cv.levels().back().dims;
  throw VolumeError(cv.root(), "even the coarsest level (" + std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" +
                                   std::to_string(d[2]) + ") exceeds the memory budget of " +
                                   std::to_string(budget_bytes >> 20) + " MiB");
}

int finest_level_of_voxels(const ChunkedVolume& cv, int from, int64_t voxels) {
  const auto& levels = cv.levels();
  int k = std::max(from, 0);
  auto count = [&](int l) {
    return double(levels[size_t(l)].dims[0]) * double(levels[size_t(l)].dims[1]) * double(levels[size_t(l)].dims[2]);
  };
  while (k + 1 < int(levels.size()) && count(k) > double(voxels)) ++k;
  return k;
}

Volume read_level(const ChunkedVolume& cv, int level, const LoadOptions& options) {
  if (level < 0 || level >= int(cv.levels().size()))
    throw VolumeError(cv.root(), "level " + std::to_string(level) + " does not exist (the pyramid has " +
                                     std::to_string(cv.levels().size()) + ")");
  const ChunkLevel& L = cv.levels()[size_t(level)];
  VolumeHeader h;
  h.dims = L.dims;
  h.spacing = L.spacing;
  h.origin = L.origin;
  h.unit = cv.unit();
  h.time_point = cv.time_point();
  h.time_points = cv.time_points();
  h.source = cv.source();
  h.big_endian = cv.big_endian();
  Dims rlo{0, 0, 0}, rhi = L.dims;
  if (options.region) {
    for (int a = 0; a < 3; ++a) {
      const auto& r = *options.region;
      if (r.lo[a] < 0 || r.hi[a] > L.dims[a] || r.lo[a] >= r.hi[a])
        throw VolumeError(cv.root(), "region [" + std::to_string(r.lo[a]) + ", " + std::to_string(r.hi[a]) +
                                         ") on axis " + std::to_string(a) + " is not inside the volume's " +
                                         std::to_string(L.dims[a]) + " voxels");
      rlo[a] = r.lo[a];
      rhi[a] = r.hi[a];
      h.dims[a] = r.hi[a] - r.lo[a];
      h.origin[a] = L.origin[a] + double(r.lo[a]) * L.spacing[a];
    }
  }
  LoadOptions local = options;
  local.region.reset();
  detail::check_header(cv.root(), h, local);
  Volume v(h);
  const size_t bpv = source_bytes(h.source);
  Dims c0{}, n{};  // the chunks that meet the box: from c0, n per axis
  for (int a = 0; a < 3; ++a) {
    c0[a] = rlo[a] / L.chunk[a];
    n[a] = (rhi[a] - 1) / L.chunk[a] + 1 - c0[a];
  }
  const double count = double(n[0]) * double(n[1]) * double(n[2]);
  if (count > double(kMaxChunksPerRead))
    throw VolumeError(cv.root(), "level " + L.name + ": " + std::to_string(int64_t(count)) + " chunks of " +
                                     std::to_string(L.chunk[0]) + "x" + std::to_string(L.chunk[1]) + "x" +
                                     std::to_string(L.chunk[2]) +
                                     " voxels for one read; chunks this small are refused");
  const int threads = decoders_within(cv, level, h, count, options);
  detail::LoadProgress progress(options, size_t(h.voxel_count()) * bpv);
  parallel_for(
      size_t(count),
      [&](size_t i) {  // rethrows the first refusal
        const int64_t k = int64_t(i);
        const Dims c{c0[0] + k % n[0], c0[1] + k / n[0] % n[1], c0[2] + k / (n[0] * n[1])};
        Dims clo{}, chi{}, rb{};
        size_t placed = bpv;
        for (int a = 0; a < 3; ++a) {
          clo[a] = c[a] * L.chunk[a];
          chi[a] = std::min(clo[a] + L.chunk[a], L.dims[a]);
          rb[a] = std::min(chi[a], rhi[a]) - std::max(clo[a], rlo[a]);
          placed *= size_t(rb[a]);
        }
        const auto bytes = cv.read_chunk(level, c);
        place_chunk(bytes ? &*bytes : nullptr, cv.fill(level), clo, chi, rlo, rhi, bpv, v.data());
        progress.add(placed);
      },
      threads);
  detail::finish_volume(cv.root(), v, h.big_endian, local);
  if (options.region) {
    v.source_dims = L.dims;
    v.region_lo = rlo;
  }
  progress.done();
  return v;
}

}  // namespace peakcast::chunked
