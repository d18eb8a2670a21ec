#include "chunked/zarr_convert.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <list>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

namespace fs = std::filesystem;

namespace peakcast::chunked {
namespace {

// The box [lo, hi) of `path` at time point t, voxels as stored, non-finite floats kept, no
// statistics; `whole`: the whole time point (a format read only whole, a TIFF stack).
Volume read_box(const fs::path& path, LoadOptions options, int64_t t, const Dims& lo, const Dims& hi,
                bool whole = false) {
  if (!whole) options.region = VoxelRegion{lo, hi};
  options.time_point = t;
  options.nonfinite = NonFinitePolicy::Keep;
  options.statistics = false;
  options.progress = nullptr;
  options.memory_budget_bytes = 0;
  options.max_voxels = std::numeric_limits<int64_t>::max();  // the budget bounds a slab, not the voxel limit
  return load_volume(path, options);
}

// Copies the box [lo, lo + box) of `v` (whose voxel (0, 0, 0) is `v_lo` of the level) into `out`
// in the source type.
void copy_box(const Volume& v, const Dims& v_lo, const Dims& lo, const Dims& box, SourceType source, uint8_t* out) {
  const size_t bpv = voxel_bytes(v.type());
  const Dims& d = v.dims();
  for (int64_t z = 0; z < box[2]; ++z)
    for (int64_t y = 0; y < box[1]; ++y) {
      uint8_t* row = out + size_t((z * box[1] + y) * box[0]) * bpv;
      const int64_t at = ((lo[2] - v_lo[2] + z) * d[1] + (lo[1] - v_lo[1] + y)) * d[0] + (lo[0] - v_lo[0]);
      std::memcpy(row, v.data() + size_t(at) * bpv, size_t(box[0]) * bpv);
      unshift_voxels(row, size_t(box[0]), source);
    }
}

// Slabs of whole z-planes of the input (a time point whole where it is read only whole), the two
// most recent kept: the writer's threads take chunks time point by time point in z order, so they
// meet at most two slabs at once.
class SlabCache {
 public:
  SlabCache(fs::path in, LoadOptions select, Dims dims, int64_t planes, std::vector<std::pair<float, float>> replace,
            bool floats, bool whole)
      : in_(std::move(in)),
        select_(std::move(select)),
        dims_(dims),
        planes_(planes),
        replace_(std::move(replace)),
        floats_(floats),
        whole_(whole) {}

  std::shared_ptr<const Volume> slab(int64_t t, int64_t index, int64_t& z0) {
    z0 = index * planes_;
    std::lock_guard lock(m_);
    for (auto& [at, v] : kept_)
      if (at == std::pair{t, index}) return v;
    if (kept_.size() >= 2) kept_.pop_back();  // before the read: two slabs at most, this one included
    auto v = std::make_shared<Volume>(
        read_box(in_, select_, t, {0, 0, z0}, {dims_[0], dims_[1], std::min(dims_[2], z0 + planes_)}, whole_));
    if (floats_ && select_.nonfinite == NonFinitePolicy::Replace)
      replace_nonfinite(*v, replace_[size_t(t)].first, replace_[size_t(t)].second);
    largest_ = std::max<int64_t>(largest_, int64_t(v->byte_size()));
    kept_.emplace_front(std::pair{t, index}, v);
    return v;
  }
  int64_t largest() const { return largest_; }

 private:
  fs::path in_;
  LoadOptions select_;
  Dims dims_;
  int64_t planes_;
  std::vector<std::pair<float, float>> replace_;  // per time point
  bool floats_, whole_;
  std::mutex m_;
  std::list<std::pair<std::pair<int64_t, int64_t>, std::shared_ptr<const Volume>>> kept_;
  int64_t largest_ = 0;
};

// A float input's finite range at time point t (a whole read replaces NaN and -Inf by its
// minimum, +Inf by its maximum) and its non-finite count, one slab at a time.
std::pair<float, float> finite_range(const fs::path& in, const LoadOptions& select, int64_t t, const Dims& dims,
                                     int64_t planes, bool whole, int64_t& nonfinite) {
  float lo = 0.f, hi = -1.f;
  bool any = false;
  nonfinite = 0;
  for (int64_t z0 = 0; z0 < dims[2]; z0 += planes) {
    const Volume v = read_box(in, select, t, {0, 0, z0}, {dims[0], dims[1], std::min(dims[2], z0 + planes)}, whole);
    const auto [a, b] = finite_extremes(v);
    if (a <= b) {
      lo = any ? std::min(lo, a) : a;
      hi = any ? std::max(hi, b) : b;
      any = true;
    }
    nonfinite += count_nonfinite(v, {0, 0, 0}, v.dims());
  }
  return any ? std::pair{lo, hi} : std::pair{0.f, 0.f};  // nothing finite: 0, as a whole read
}

// The level below level k as written (in `partial`, an OME-Zarr of the levels so far), halved
// into the box [lo, lo + box) of level k at time point t, in the source type.
void halve_from_below(const fs::path& partial, const VolumeHeader& h, int k, int64_t t, const Dims& lo, const Dims& box,
                      uint8_t* dst) {
  Dims below_dims = h.dims, below_lo{}, below_hi{};
  for (int j = 1; j < k; ++j)
    for (auto& x : below_dims) x = (x + 1) / 2;
  for (int a = 0; a < 3; ++a) {  // the 2x2x2 blocks of this box (an odd edge is the level's own)
    below_lo[a] = 2 * lo[a];
    below_hi[a] = std::min(2 * (lo[a] + box[a]), below_dims[a]);
  }
  LoadOptions level;
  level.level = k - 1;
  const Volume below = read_box(partial, level, t, below_lo, below_hi);
  const VoxelType type = below.type();
  Dims half{};
  const std::vector<uint8_t> means = halve_voxels(type, below.dims(), below.data(), half);
  if (half != box) throw std::logic_error("convert: a level's box is not half the one below");
  std::memcpy(dst, means.data(), means.size());
  const size_t bpv = voxel_bytes(type);
  for (int64_t row = 0; row < box[1] * box[2]; ++row)
    unshift_voxels(dst + size_t(row * box[0]) * bpv, size_t(box[0]), h.source);
}

// The header of `v`, a read of the whole volume's `dims` (a region read holds fewer).
VolumeHeader header_of(const Volume& v, const Dims& dims) {
  VolumeHeader h;
  h.dims = dims;
  h.spacing = v.spacing;
  h.origin = v.origin;
  h.unit = v.unit;
  h.source = v.source_type();
  h.time_point = v.time_point;
  h.time_points = v.time_points;
  return h;
}

}  // namespace

int64_t source_voxel_bytes(const fs::path& in, const LoadOptions& select, VolumeHeader* header) {
  const Volume head = read_box(in, select, select.time_point, {0, 0, 0}, {1, 1, 1});
  const Dims& d = head.source_dims;
  if (header) *header = header_of(head, d);
  return d[0] * d[1] * d[2] * int64_t(voxel_bytes(head.type()));
}

namespace {

// The header of `in` and whether it is read only whole (then from a whole read of its first
// time point: a TIFF stack has no region reads).
VolumeHeader input_header(const fs::path& in, const LoadOptions& select, bool& whole) {
  VolumeHeader h;
  whole = false;
  try {
    source_voxel_bytes(in, select, &h);
  } catch (const RegionNotReadable&) {
    whole = true;
    const Volume v = read_box(in, select, select.time_point, {}, {}, true);
    h = header_of(v, v.dims());
  }
  return h;
}

}  // namespace

SlabConvertReport convert_to_ome_zarr_by_slabs(const fs::path& in, const fs::path& out, const LoadOptions& select,
                                               const ZarrWriteOptions& options, int64_t budget_bytes, bool series) {
  if (options.chunk < 1 || options.chunk > 512) throw std::invalid_argument("chunk edge must be 1..512 voxels");
  if (budget_bytes <= 0) throw std::invalid_argument("the memory budget must be positive");
  std::error_code ec;
  if (fs::exists(out, ec)) throw VolumeError(out, "already exists (remove it first)");  // before any pass
  SlabConvertReport r;
  bool whole = false;
  r.header = input_header(in, select, whole);
  VolumeHeader& h = r.header;
  const int64_t first = series ? 0 : h.time_point, times = series ? std::max<int64_t>(h.time_points, 1) : 1;
  h.time_points = times;  // what is written: every time point, or the one selected
  const Dims& dims = h.dims;
  const VoxelType type = storage_type(h.source);
  const int64_t plane_bytes = dims[0] * dims[1] * int64_t(voxel_bytes(type));
  const int64_t edge = std::min(options.chunk, dims[2]);  // level 0's chunks in z: a slab holds whole ones
  r.slab_planes =
      whole ? dims[2]
            : std::min(dims[2],
                       std::max<int64_t>(edge, budget_bytes / 2 / std::max<int64_t>(plane_bytes, 1) / edge * edge));

  std::vector<std::pair<float, float>> replace(size_t(first + times), {0.f, 0.f});
  const bool floats = type == VoxelType::F32;
  if (floats && select.nonfinite != NonFinitePolicy::Keep) {
    r.passes = 2;
    for (int64_t t = first; t < first + times; ++t) {
      int64_t nonfinite = 0;
      replace[size_t(t)] = finite_range(in, select, t, dims, r.slab_planes, whole, nonfinite);
      if (nonfinite > 0 && select.nonfinite == NonFinitePolicy::Refuse)
        throw VolumeError(in, std::to_string(nonfinite) + " voxels are NaN or Inf (nonfinite: refuse)");
    }
  }
  SlabCache slabs(in, select, dims, r.slab_planes, replace, floats, whole);
  const fs::path partial = partial_path(out);
  const int levels = options.pyramid ? pyramid_levels(dims, options.chunk) : 1;
  const std::string name = in.filename().string();
  r.zarr = write_ome_zarr_levels(out, h, levels, name, options,
                                 [&](int k, int64_t t, const Dims& lo, const Dims& box, uint8_t* dst) {
                                   if (k > 0) return halve_from_below(partial, h, k, t, lo, box, dst);
                                   int64_t z0 = 0;
                                   const auto slab = slabs.slab(first + t, lo[2] / r.slab_planes, z0);
                                   copy_box(*slab, {0, 0, z0}, lo, box, h.source, dst);
                                 });
  r.slab_bytes = slabs.largest();
  return r;
}

}  // namespace peakcast::chunked
