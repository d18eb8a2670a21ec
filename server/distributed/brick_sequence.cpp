#include "distributed/brick_sequence.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <memory>
#include <stdexcept>

#include "core/macrocell_share.h"
#include "distributed/brick_frame.h"

namespace peakcast::distributed {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

int64_t largest_read(const KdSplit& s) {
  int64_t m = 0;
  for (const Brick& b : s.bricks) m = std::max(m, b.voxels_read());
  return m;
}

// One brick's voxels as the whole volume's brick: NaN/Inf kept for the caller to replace.
std::shared_ptr<Volume> read_brick_voxels(const std::string& path, const LoadOptions& base, const Brick& b) {
  LoadOptions o = base;
  o.region = VoxelRegion{b.read_lo, b.read_hi};
  o.nonfinite = NonFinitePolicy::Keep;
  o.progress = nullptr;
  o.statistics = false;  // the caller has (or reduces) the whole volume's
  return std::make_shared<Volume>(load_volume(path, o));
}

int64_t count_nonfinite(const Volume& v, const Index3& lo, const Index3& hi) {
  if (v.type() != VoxelType::F32) return 0;
  const auto* p = reinterpret_cast<const float*>(v.data());
  int64_t n = 0;
  for (int64_t k = lo[2]; k < hi[2]; ++k)
    for (int64_t j = lo[1]; j < hi[1]; ++j)
      for (int64_t i = lo[0]; i < hi[0]; ++i) n += !std::isfinite(p[(k * v.dims()[1] + j) * v.dims()[0] + i]);
  return n;
}

// The brick's voxels with NaN/Inf as one process replaces them (finite extremes of the whole).
void replace_with(Volume& v, const SequenceStatistics& s) {
  const float lo = float(s.box.min_value - v.value_offset), hi = float(s.box.max_value - v.value_offset);
  replace_nonfinite(v, lo, hi);
}

// The bricks' share of a budget: the rest holds the chunks being decoded, the image layers and
// the grids (bench outofcore: 1 GiB of voxels in 9 bricks under 256 MiB peaked 1 MiB past the
// budget plus 10% with the whole budget given to bricks).
int64_t voxel_share(int64_t budget_bytes) { return budget_bytes / 10 * 9; }

}  // namespace

int bricks_for_budget(const Index3& dims, int ghost, size_t voxel_bytes, int64_t budget_bytes, int holding) {
  auto fits = [&](int n) {
    return double(largest_read(kd_split(dims, n, ghost))) * double(voxel_bytes) * holding <= double(budget_bytes);
  };
  // No fewer bricks than the bytes need; no more than kMaxBricks (a budget of a few bytes is
  // refused before a split into millions of bricks is tried).
  constexpr int kMaxBricks = 1 << 20;
  const double need = double(dims[0]) * double(dims[1]) * double(dims[2]) * double(voxel_bytes) * holding;
  const double least = std::ceil(need / std::max(double(budget_bytes), 1.0));
  int hi = int(std::clamp(least, 1.0, double(kMaxBricks) + 1.0));
  try {
    while (hi <= kMaxBricks && !fits(hi)) hi = hi * 2 > kMaxBricks && hi < kMaxBricks ? kMaxBricks : hi * 2;
    if (hi > kMaxBricks) throw std::invalid_argument("too many bricks");
  } catch (const std::invalid_argument&) {  // the split ran out of planes to cut
    char mib[32];
    std::snprintf(mib, sizeof mib, "%.2f", double(budget_bytes) / 1048576.0);
    throw std::invalid_argument(std::string("a memory budget of ") + mib + " MiB cannot hold " +
                                std::to_string(holding) + " bricks of this volume with their ghost voxels");
  }
  int lo = std::max(int(least), hi / 2 + 1);  // the fewest that fits lies in [lo, hi]
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (fits(mid)) hi = mid;
    else lo = mid + 1;
  }
  return hi;
}

SequenceStatistics sequence_statistics(const std::string& path, const LoadOptions& base, int64_t budget_bytes,
                                       const std::function<void(double)>& progress) {
  const auto t0 = Clock::now();
  SequenceStatistics s;
  LoadOptions one = base;
  one.region = VoxelRegion{{0, 0, 0}, {1, 1, 1}};
  one.progress = nullptr;
  const Volume head = load_volume(path, one);
  const Index3 dims{head.source_dims[0], head.source_dims[1], head.source_dims[2]};
  s.box = VolumeBox{dims, head.spacing, head.origin, 0.0, 0.0, {}};
  s.source = head.source_type();
  const size_t bpv = voxel_bytes(head.type());
  s.bricks = bricks_for_budget(dims, 0, bpv, voxel_share(budget_bytes), 1);
  const KdSplit split = kd_split(dims, s.bricks, 0);
  MacrocellShare shares[2];
  const FilterSupport supports[2] = {FilterSupport::Trilinear, FilterSupport::Tricubic};
  auto add_shares = [&](const Volume& v, size_t k) {
    for (int g = 0; g < 2; ++g) {
      MacrocellShare share = brick_macrocell_share(v, split.bricks[k], dims, supports[g]);
      if (k == 0) shares[g] = std::move(share);
      else add_share(shares[g], share);
    }
  };
  if (head.type() != VoxelType::F32) {
    // Integers: one pass. Each stored value's count gives the range and the histogram exactly
    // (Volume::histogram_of_counts); the macrocell shares need no range.
    std::vector<uint64_t> counts;
    for (size_t k = 0; k < split.bricks.size(); ++k) {
      const auto v = read_brick_voxels(path, base, split.bricks[k]);
      s.bytes_read += int64_t(v->byte_size());
      const auto [own_lo, own_hi] = counted_box(split.bricks[k], dims);
      const auto c = v->box_value_counts(Dims{own_lo[0], own_lo[1], own_lo[2]}, Dims{own_hi[0], own_hi[1], own_hi[2]});
      if (counts.empty()) counts.assign(c.size(), 0);
      for (size_t i = 0; i < c.size(); ++i) counts[i] += c[i];
      add_shares(*v, k);
      if (progress) progress(double(k + 1) / double(split.bricks.size()));
    }
    size_t lo = 0, hi = counts.size() - 1;
    while (lo < counts.size() && counts[lo] == 0) ++lo;
    while (hi > lo && counts[hi] == 0) --hi;
    const double offset = storage_offset(head.source_type());
    s.box.min_value = double(lo) + offset;
    s.box.max_value = double(hi) + offset;
    s.box.histogram = Volume::histogram_of_counts(counts, double(lo), double(hi));
  } else {
    const double steps = 2.0 * double(split.bricks.size());
    // Pass 1: the finite range and the non-finite count.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (size_t k = 0; k < split.bricks.size(); ++k) {
      const auto v = read_brick_voxels(path, base, split.bricks[k]);
      s.bytes_read += int64_t(v->byte_size());
      const auto [own_lo, own_hi] = counted_box(split.bricks[k], dims);
      s.nonfinite += count_nonfinite(*v, own_lo, own_hi);
      const auto [f_lo, f_hi] = finite_extremes(*v);
      if (f_lo <= f_hi) {
        lo = std::min(lo, double(f_lo));
        hi = std::max(hi, double(f_hi));
      }
      if (progress) progress(double(k + 1) / steps);
    }
    if (s.nonfinite > 0 && base.nonfinite == NonFinitePolicy::Refuse)
      throw VolumeError(path, std::to_string(s.nonfinite) + " NaN/Inf voxels (policy: refuse)");
    if (!(lo <= hi)) lo = hi = 0.0;  // nothing finite anywhere: 0, as one process
    s.box.min_value = lo;
    s.box.max_value = hi;
    // Pass 2: the histogram over that range and the macrocell grids, each voxel counted once.
    std::vector<uint64_t> histogram(Volume::kHistogramBins, 0);
    for (size_t k = 0; k < split.bricks.size(); ++k) {
      const auto v = read_brick_voxels(path, base, split.bricks[k]);
      s.bytes_read += int64_t(v->byte_size());
      replace_with(*v, s);
      const auto [own_lo, own_hi] = counted_box(split.bricks[k], dims);
      const auto h = v->box_histogram(Dims{own_lo[0], own_lo[1], own_lo[2]}, Dims{own_hi[0], own_hi[1], own_hi[2]}, lo, hi);
      for (size_t i = 0; i < h.size(); ++i) histogram[i] += h[i];
      add_shares(*v, k);
      if (progress) progress(double(split.bricks.size() + k + 1) / steps);
    }
    s.box.histogram = std::move(histogram);
  }
  s.cells.trilinear = std::make_shared<const MacrocellGrid>(grid_from_share(shares[0]));
  s.cells.tricubic = std::make_shared<const MacrocellGrid>(grid_from_share(shares[1]));
  s.ms = ms_since(t0);
  return s;
}

SequenceResult render_sequence(render::Renderer& renderer, const std::string& path, const LoadOptions& base,
                               const SequenceStatistics& stats, const ResolvedScene& scene, int64_t budget_bytes,
                               const std::function<void(double)>& progress) {
  SequenceResult r;
  const Index3& dims = stats.box.dims;
  r.ghost = brick_ghost(scene);
  const size_t bpv = voxel_bytes(storage_type(stats.source));
  r.bricks = bricks_for_budget(dims, r.ghost, bpv, voxel_share(budget_bytes), 2);
  const KdSplit split = kd_split(dims, r.bricks, r.ghost);
  r.largest_brick_bytes = largest_read(split) * int64_t(bpv);
  const glm::dvec3 eye = (scene.camera.eye - stats.box.origin) / stats.box.spacing;
  const glm::dvec3 dir = glm::normalize((scene.camera.center - scene.camera.eye) / stats.box.spacing);
  const std::vector<int> order = visibility_order(split, eye, dir, scene.camera.orthographic);
  const int w = scene.scene.width, h = scene.scene.height;
  std::vector<float> acc(size_t(w) * size_t(h) * 4, 0.f);
  std::shared_ptr<const std::vector<float>> front;
  auto read = [&](int k) {
    const auto t = Clock::now();
    auto v = read_brick_voxels(path, base, split.bricks[size_t(k)]);
    replace_with(*v, stats);
    v->min_value = stats.box.min_value;  // the whole volume's range and histogram, as a rank's brick
    v->max_value = stats.box.max_value;
    v->histogram = stats.box.histogram;
    return std::make_pair(v, ms_since(t));
  };
  std::future<std::pair<std::shared_ptr<Volume>, double>> next = std::async(std::launch::async, read, order[0]);
  for (size_t i = 0; i < order.size(); ++i) {
    auto [voxels, read_ms] = next.get();
    r.read_ms += read_ms;
    r.bytes_read += int64_t(voxels->byte_size());
    if (i + 1 < order.size()) next = std::async(std::launch::async, read, order[i + 1]);  // read-ahead
    const auto t = Clock::now();
    auto resident = renderer.make_resident(voxels, stats.cells);
    voxels.reset();
    resident->drop_host_voxels();
    render::Brick b = frame_brick(split.bricks[size_t(order[i])], dims);
    if (scene.ray_texture) b.front_opacity = front;
    const Image layer = renderer.render_brick(*resident, scene, b);
    resident.reset();
    if (scene.ray_texture) front = std::make_shared<const std::vector<float>>(opacity_over(front.get(), layer));
    acc = composite_over({acc, layer.rgba}, {0, 1});
    r.render_ms += ms_since(t);
    if (progress) progress(double(i + 1) / double(order.size()));
  }
  r.image = finish_composite(acc, w, h, scene.scene.background);
  return r;
}

}  // namespace peakcast::distributed
