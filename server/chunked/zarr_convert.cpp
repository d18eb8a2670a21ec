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

// The box [lo, hi) of `path`, voxels as stored, non-finite floats kept, no statistics.
Volume read_box(const fs::path& path, LoadOptions options, const Dims& lo, const Dims& hi) {
  options.region = VoxelRegion{lo, hi};
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

// Slabs of whole z-planes of the input, the two most recent kept: the writer's threads take
// chunks in z order, so they meet at most two slabs at once.
class SlabCache {
 public:
  SlabCache(fs::path in, LoadOptions select, Dims dims, int64_t planes, std::pair<float, float> replace, bool floats)
      : in_(std::move(in)),
        select_(std::move(select)),
        dims_(dims),
        planes_(planes),
        replace_(replace),
        floats_(floats) {}

  std::shared_ptr<const Volume> slab(int64_t index, int64_t& z0) {
    z0 = index * planes_;
    std::lock_guard lock(m_);
    for (auto& [i, v] : kept_)
      if (i == index) return v;
    if (kept_.size() >= 2) kept_.pop_back();  // before the read: two slabs at most, this one included
    auto v = std::make_shared<Volume>(
        read_box(in_, select_, {0, 0, z0}, {dims_[0], dims_[1], std::min(dims_[2], z0 + planes_)}));
    if (floats_ && select_.nonfinite == NonFinitePolicy::Replace)
      replace_nonfinite(*v, replace_.first, replace_.second);
    largest_ = std::max<int64_t>(largest_, int64_t(v->byte_size()));
    kept_.emplace_front(index, v);
    return v;
  }
  int64_t largest() const { return largest_; }

 private:
  fs::path in_;
  LoadOptions select_;
  Dims dims_;
  int64_t planes_;
  std::pair<float, float> replace_;
  bool floats_;
  std::mutex m_;
  std::list<std::pair<int64_t, std::shared_ptr<const Volume>>> kept_;
  int64_t largest_ = 0;
};

// A float input's finite range (a whole read replaces NaN and -Inf by its minimum, +Inf by its
// maximum) and its non-finite count, one slab at a time.
std::pair<float, float> finite_range(const fs::path& in, const LoadOptions& select, const Dims& dims, int64_t planes,
                                     int64_t& nonfinite) {
  float lo = 0.f, hi = -1.f;
  bool any = false;
  nonfinite = 0;
  for (int64_t z0 = 0; z0 < dims[2]; z0 += planes) {
    const Volume v = read_box(in, select, {0, 0, z0}, {dims[0], dims[1], std::min(dims[2], z0 + planes)});
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

}  // namespace

int64_t source_voxel_bytes(const fs::path& in, const LoadOptions& select, VolumeHeader* header) {
  const Volume head = read_box(in, select, {0, 0, 0}, {1, 1, 1});
  const Dims& d = head.source_dims;
  if (header) {
    header->dims = d;
    header->spacing = head.spacing;
    header->origin = head.origin;
    header->unit = head.unit;
    header->source = head.source_type();
  }
  return d[0] * d[1] * d[2] * int64_t(voxel_bytes(head.type()));
}

SlabConvertReport convert_to_ome_zarr_by_slabs(const fs::path& in, const fs::path& out, const LoadOptions& select,
                                               const ZarrWriteOptions& options, int64_t budget_bytes) {
  if (options.chunk < 1 || options.chunk > 512) throw std::invalid_argument("chunk edge must be 1..512 voxels");
  if (budget_bytes <= 0) throw std::invalid_argument("the memory budget must be positive");
  std::error_code ec;
  if (fs::exists(out, ec)) throw VolumeError(out, "already exists (remove it first)");  // before any pass
  SlabConvertReport r;
  source_voxel_bytes(in, select, &r.header);
  const VolumeHeader& h = r.header;
  const Dims& dims = h.dims;
  const VoxelType type = storage_type(h.source);
  const int64_t plane_bytes = dims[0] * dims[1] * int64_t(voxel_bytes(type));
  const int64_t edge = std::min(options.chunk, dims[2]);  // level 0's chunks in z: a slab holds whole ones
  r.slab_planes = std::max<int64_t>(edge, budget_bytes / 2 / std::max<int64_t>(plane_bytes, 1) / edge * edge);

  std::pair<float, float> replace{0.f, 0.f};
  const bool floats = type == VoxelType::F32;
  if (floats && select.nonfinite != NonFinitePolicy::Keep) {
    int64_t nonfinite = 0;
    replace = finite_range(in, select, dims, r.slab_planes, nonfinite);
    r.passes = 2;
    if (nonfinite > 0 && select.nonfinite == NonFinitePolicy::Refuse)
      throw VolumeError(in, std::to_string(nonfinite) + " voxels are NaN or Inf (nonfinite: refuse)");
  }
  SlabCache slabs(in, select, dims, r.slab_planes, replace, floats);
  const fs::path partial = partial_path(out);
  const int levels = options.pyramid ? pyramid_levels(dims, options.chunk) : 1;
  const std::string name = in.filename().string();
  r.zarr =
      write_ome_zarr_levels(out, h, levels, name, options, [&](int k, const Dims& lo, const Dims& box, uint8_t* dst) {
        if (k == 0) {
          int64_t z0 = 0;
          const auto slab = slabs.slab(lo[2] / r.slab_planes, z0);
          return copy_box(*slab, {0, 0, z0}, lo, box, h.source, dst);
        }
        // The level below as written: the 2x2x2 blocks of this box (an odd edge is the level's
        // own).
        Dims below_dims = dims, below_lo{}, below_hi{};
        for (int j = 1; j < k; ++j)
          for (auto& x : below_dims) x = (x + 1) / 2;
        for (int a = 0; a < 3; ++a) {
          below_lo[a] = 2 * lo[a];
          below_hi[a] = std::min(2 * (lo[a] + box[a]), below_dims[a]);
        }
        const Volume below = read_box(partial / std::to_string(k - 1), {}, below_lo, below_hi);
        Dims half{};
        const std::vector<uint8_t> means = halve_voxels(type, below.dims(), below.data(), half);
        if (half != box) throw std::logic_error("convert: a level's box is not half the one below");
        std::memcpy(dst, means.data(), means.size());
        const size_t bpv = voxel_bytes(type);
        for (int64_t row = 0; row < box[1] * box[2]; ++row)
          unshift_voxels(dst + size_t(row * box[0]) * bpv, size_t(box[0]), h.source);
      });
  r.slab_bytes = slabs.largest();
  return r;
}

}  // namespace peakcast::chunked
