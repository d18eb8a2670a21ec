#include "distributed/brick_sequence.h"

#include <malloc.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include "core/macrocell_share.h"
#include "core/parallel.h"
#include "core/value_counts.h"
#include "distributed/brick_frame.h"

namespace peakcast::distributed {
using Clock = std::chrono::steady_clock;
namespace {

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

// The brick's voxels with NaN/Inf as one process replaces them (finite extremes of the whole).
void replace_with(Volume& v, const SequenceStatistics& s) {
  const float lo = float(s.box.min_value - v.value_offset), hi = float(s.box.max_value - v.value_offset);
  replace_nonfinite(v, lo, hi);
}

// The bricks' share of a budget: the rest holds the chunks being decoded, the image layers and
// the grids (bench outofcore: 1 GiB of voxels in 9 bricks under 256 MiB peaked 1 MiB past the
// budget plus 10% with the whole budget given to bricks).
int64_t voxel_share(int64_t budget_bytes) { return budget_bytes / 10 * 9; }

// What the budget holds beside the bricks that does not shrink with them, taken from their share
// first: a budget too small for it (a few KiB in tests) still gives the bricks half their share.
// too_small: the budget held more than it says (budget_too_small).
int64_t bricks_share(int64_t budget_bytes, int64_t beside, bool& too_small) {
  const int64_t share = voxel_share(budget_bytes);
  too_small = share - beside < share / 2;
  return std::max(share - beside, share / 2);
}

// The whole volume's macrocells: up to 64 per axis (default_cell_size), whatever the bricks.
int64_t macrocell_count(const Index3& dims) {
  const Dims d{dims[0], dims[1], dims[2]};
  const int cell = default_cell_size(d);
  return cells_along(d[0], cell) * cells_along(d[1], cell) * cells_along(d[2], cell);
}
// A share per cell: min, max (float), own count, sum, sum of squares (double); a grid: min, max, stddev.
constexpr int64_t kShareCellBytes = 2 * sizeof(float) + 3 * sizeof(double);
constexpr int64_t kGridCellBytes = 3 * sizeof(float);

// Statistics hold beside each brick: the two grids' shares, to which each brick adds its voxels
// (bench outofcore's 4096^3 pyramid: 64^3 cells, 16 MiB), and for integers the count
// of each stored value, per table and summed (65536 counts for 16-bit voxels, at most 4 tables).
int64_t statistics_beside(const Index3& dims, VoxelType type) {
  const int64_t values = type == VoxelType::U8 ? 256 : type == VoxelType::U16 ? 65536 : Volume::kHistogramBins;
  return 2 * macrocell_count(dims) * kShareCellBytes +
         (value_count_tables(type) + 2) * values * int64_t(sizeof(uint64_t));
}

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
    if (fits(mid))
      hi = mid;
    else
      lo = mid + 1;
  }
  return hi;
}

StatisticsRun::StatisticsRun(std::string path, LoadOptions base, int64_t budget_bytes)
    : path_(std::move(path)), base_(std::move(base)), t0_(Clock::now()) {
  LoadOptions one = base_;
  one.region = VoxelRegion{{0, 0, 0}, {1, 1, 1}};
  one.progress = nullptr;
  const Volume head = load_volume(path_, one);
  dims_ = Index3{head.source_dims[0], head.source_dims[1], head.source_dims[2]};
  s_.box = VolumeBox{dims_, head.spacing, head.origin, 0.0, 0.0, {}};
  s_.source = head.source_type();
  floats_ = head.type() == VoxelType::F32;
  offset_ = storage_offset(head.source_type());
  const int64_t beside = statistics_beside(dims_, head.type());
  const int64_t share = bricks_share(budget_bytes, beside, s_.budget_too_small);
  s_.bricks = bricks_for_budget(dims_, 0, voxel_bytes(head.type()), share, 1);
  split_ = kd_split(dims_, s_.bricks, 0);
  if (floats_) histogram_.assign(Volume::kHistogramBins, 0);
  if (floats_) border_histogram_.assign(Volume::kHistogramBins, 0);
}

StatisticsRun::~StatisticsRun() = default;

int StatisticsRun::total_steps() const { return int(split_.bricks.size()) * (floats_ ? 2 : 1); }

double StatisticsRun::progress() const { return double(steps_) / double(total_steps()); }

bool StatisticsRun::done() const { return steps_ >= total_steps(); }

void StatisticsRun::add_shares(const Volume& v, size_t k) {
  const auto [lo, hi] = counted_box(split_.bricks[k], dims_);
  add_macrocell_shares_at(shares_[0], shares_[1], v, v.region_lo, Dims{dims_[0], dims_[1], dims_[2]},
                          Dims{lo[0], lo[1], lo[2]}, Dims{hi[0], hi[1], hi[2]});
}

void StatisticsRun::step() {
  if (done()) return;
  const size_t n = split_.bricks.size(), k = size_t(steps_) % n;
  const bool second_pass = size_t(steps_) >= n;
  const auto v = read_brick_voxels(path_, base_, split_.bricks[k]);
  s_.bytes_read += int64_t(v->byte_size());
  const auto [own_lo, own_hi] = counted_box(split_.bricks[k], dims_);
  const Dims lo{own_lo[0], own_lo[1], own_lo[2]}, hi{own_hi[0], own_hi[1], own_hi[2]};
  if (!floats_) {
    // Integers: one pass. Each stored value's count gives the range and the histogram exactly
    // (Volume::histogram_of_counts); the macrocell shares need no range.
    const auto c = v->box_value_counts(lo, hi);
    if (counts_.empty()) counts_.assign(c.size(), 0);
    for (size_t i = 0; i < c.size(); ++i) counts_[i] += c[i];
    if (border_counts_.empty()) border_counts_.assign(c.size(), 0);
    const auto [face_lo, face_hi] = whole_faces(split_.bricks[k], dims_);
    v->for_each_border_voxel(lo, hi, face_lo, face_hi, [&](double x) { ++border_counts_[size_t(x)]; });
    add_shares(*v, k);
  } else if (!second_pass) {
    // Floats, pass 1: the finite range and the non-finite count.
    s_.nonfinite += count_nonfinite(*v, own_lo, own_hi);
    const auto [f_lo, f_hi] = finite_extremes(*v);
    if (f_lo <= f_hi) {
      lo_ = std::min(lo_, double(f_lo));
      hi_ = std::max(hi_, double(f_hi));
    }
  } else {
    // Pass 2: the histogram over that range and the macrocell grids, each voxel counted once.
    replace_with(*v, s_);
    const auto h = v->box_histogram(lo, hi, s_.box.min_value, s_.box.max_value);
    for (size_t i = 0; i < h.size(); ++i) histogram_[i] += h[i];
    const auto [face_lo, face_hi] = whole_faces(split_.bricks[k], dims_);
    const auto e = v->box_border_histogram(lo, hi, face_lo, face_hi, s_.box.min_value, s_.box.max_value);
    for (size_t i = 0; i < e.size(); ++i) border_histogram_[i] += e[i];
    add_shares(*v, k);
  }
  steps_++;
  if (floats_ && size_t(steps_) == n) {  // the first pass is over: the range the second uses
    if (s_.nonfinite > 0 && base_.nonfinite == NonFinitePolicy::Refuse)
      throw VolumeError(path_, std::to_string(s_.nonfinite) + " NaN/Inf voxels (policy: refuse)");
    if (!(lo_ <= hi_)) lo_ = hi_ = 0.0;  // nothing finite anywhere: 0, as one process
    s_.box.min_value = lo_;
    s_.box.max_value = hi_;
  }
  if (done()) finish();
}

void StatisticsRun::finish() {
  if (!floats_) {
    size_t lo = 0, hi = counts_.size() - 1;
    while (lo < counts_.size() && counts_[lo] == 0) ++lo;
    while (hi > lo && counts_[hi] == 0) --hi;
    s_.box.min_value = double(lo) + offset_;
    s_.box.max_value = double(hi) + offset_;
    s_.box.histogram = Volume::histogram_of_counts(counts_, double(lo), double(hi));
    s_.box.border_histogram = Volume::histogram_of_counts(border_counts_, double(lo), double(hi));
  } else {
    s_.box.histogram = std::move(histogram_);
    s_.box.border_histogram = std::move(border_histogram_);
  }
  s_.cells.trilinear = std::make_shared<const MacrocellGrid>(grid_from_share(shares_[0]));
  s_.cells.tricubic = std::make_shared<const MacrocellGrid>(grid_from_share(shares_[1]));
  // The shares and counts (a few MiB: statistics_beside) go back to the system, not to a heap
  // arena that the bricks drawn next, read on other threads, would not take them from.
  shares_[0] = shares_[1] = MacrocellShare{};
  std::vector<uint64_t>().swap(counts_);
  std::vector<uint64_t>().swap(border_counts_);
  std::vector<uint64_t>().swap(histogram_);
  malloc_trim(0);
  s_.ms = ms_since(t0_);
}

SequenceStatistics StatisticsRun::take() {
  if (!done()) throw std::logic_error("StatisticsRun::take before the last brick");
  return std::move(s_);
}

SequenceStatistics sequence_statistics(const std::string& path, const LoadOptions& base, int64_t budget_bytes,
                                       const std::function<void(double)>& progress) {
  StatisticsRun run(path, base, budget_bytes);
  while (!run.done()) {
    run.step();
    if (progress) progress(run.progress());
  }
  return run.take();
}

int image_tiles(const ResolvedScene& scene, int64_t budget_bytes) {
  const double row_bytes = 8.0 * double(scene.scene.width) * 4.0 * double(sizeof(float));
  const double rows = std::max(1.0, std::floor(double(std::max<int64_t>(budget_bytes, 1)) / 4.0 / row_bytes));
  const int needed = int(std::min<double>(scene.scene.height, std::ceil(double(scene.scene.height) / rows)));
  return needed <= kMaxImageTiles ? needed : 1;
}

render::PixelRect image_tile(const ResolvedScene& scene, int t, int tiles) {
  const int64_t h = scene.scene.height;
  const int y0 = int(h * t / tiles), y1 = int(h * (t + 1) / tiles);
  return {0, y0, scene.scene.width, y1 - y0};
}

SequenceRun::SequenceRun(std::string path, LoadOptions base, std::shared_ptr<const SequenceStatistics> stats,
                         ResolvedScene scene, int64_t budget_bytes, std::optional<render::PixelRect> rect)
    : path_(std::move(path)),
      base_(std::move(base)),
      stats_(std::move(stats)),
      scene_(std::move(scene)),
      rect_(rect ? *rect : render::PixelRect{0, 0, scene_.scene.width, scene_.scene.height}) {
  const Index3& dims = stats_->box.dims;
  r_.ghost = brick_ghost(scene_);
  const size_t bpv = voxel_bytes(storage_type(stats_->source));
  // The image's buffers come out of the budget first: the layers composited so far, the brick's
  // layer, the composite being made, the renderer's own buffers and what the allocator keeps of
  // them. Measured (bench outofcore --size 1024 --budget-mib 256 --image 1024): 130 MiB beyond
  // the two bricks at 1024², eight RGBA float images. The whole volume's two grids stay beside.
  const int64_t image_bytes = 8 * int64_t(rect_.w) * rect_.h * 4 * int64_t(sizeof(float));
  const int64_t grid_bytes = 2 * macrocell_count(dims) * kGridCellBytes;
  r_.beside_bytes = image_bytes + grid_bytes;
  const int64_t share = bricks_share(budget_bytes, r_.beside_bytes, r_.budget_too_small);
  r_.bricks = bricks_for_budget(dims, r_.ghost, bpv, share, 2);
  split_ = kd_split(dims, r_.bricks, r_.ghost);
  r_.largest_brick_bytes = largest_read(split_) * int64_t(bpv);
  const glm::dvec3 eye = (scene_.camera.eye - stats_->box.origin) / stats_->box.spacing;
  const glm::dvec3 dir = glm::normalize((scene_.camera.center - scene_.camera.eye) / stats_->box.spacing);
  order_ = visibility_order(split_, eye, dir, scene_.camera.orthographic);
  acc_.assign(size_t(rect_.w) * size_t(rect_.h) * 4, 0.f);
  next_ = read_ahead(order_[0]);
}

SequenceRun::~SequenceRun() {
  if (next_.valid()) next_.wait();  // a read in flight uses this object's members
}

std::future<SequenceRun::Read> SequenceRun::read_ahead(int k) {
  return std::async(std::launch::async, [this, k] {
    const auto t = Clock::now();
    auto v = read_brick_voxels(path_, base_, split_.bricks[size_t(k)]);
    replace_with(*v, *stats_);
    v->min_value = stats_->box.min_value;  // the whole volume's range and histogram, as a rank's brick
    v->max_value = stats_->box.max_value;
    v->histogram = stats_->box.histogram;
    v->border_histogram = stats_->box.border_histogram;
    return Read{std::move(v), ms_since(t)};
  });
}

bool SequenceRun::done() const { return next_brick_ >= order_.size(); }

double SequenceRun::progress() const { return double(next_brick_) / double(order_.size()); }

void SequenceRun::step(render::Renderer& renderer) {
  if (done()) return;
  auto [voxels, read_ms] = next_.get();
  r_.read_ms += read_ms;
  r_.bytes_read += int64_t(voxels->byte_size());
  const size_t i = next_brick_++;
  if (i + 1 < order_.size()) next_ = read_ahead(order_[i + 1]);  // read-ahead
  const auto t = Clock::now();
  auto resident = renderer.make_resident(voxels, stats_->cells);
  voxels.reset();
  resident->drop_host_voxels();
  render::Brick b = frame_brick(split_.bricks[size_t(order_[i])], stats_->box.dims);
  if (scene_.ray_texture) b.front_opacity = front_;
  const Image layer = renderer.render_brick(*resident, scene_, b, nullptr, rect_);
  resident.reset();
  if (scene_.ray_texture) front_ = std::make_shared<const std::vector<float>>(opacity_over(front_.get(), layer));
  acc_ = composite_over({acc_, layer.rgba}, {0, 1});
  r_.render_ms += ms_since(t);
}

SequenceResult SequenceRun::take() {
  if (!done()) throw std::logic_error("SequenceRun::take before the last brick");
  r_.image = finish_composite(acc_, rect_.w, rect_.h, scene_.scene.background);
  return std::move(r_);
}

void add_tile(SequenceResult& all, SequenceResult tile, const render::PixelRect& rect, const ResolvedScene& scene) {
  if (all.image.width == 0) all.image = Image(scene.scene.width, scene.scene.height);
  render::place_tile(all.image, rect, tile.image);
  all.bricks = tile.bricks;
  all.ghost = tile.ghost;
  all.bytes_read += tile.bytes_read;
  all.largest_brick_bytes = std::max(all.largest_brick_bytes, tile.largest_brick_bytes);
  all.read_ms += tile.read_ms;
  all.render_ms += tile.render_ms;
  all.beside_bytes = std::max(all.beside_bytes, tile.beside_bytes);
  all.budget_too_small = all.budget_too_small || tile.budget_too_small;
}

SequenceResult render_sequence(render::Renderer& renderer, const std::string& path, const LoadOptions& base,
                               const SequenceStatistics& stats, const ResolvedScene& scene, int64_t budget_bytes,
                               const std::function<void(double)>& progress) {
  const int tiles = image_tiles(scene, budget_bytes);
  const auto shared = std::make_shared<const SequenceStatistics>(stats);
  SequenceResult all;
  for (int t = 0; t < tiles; ++t) {
    const render::PixelRect rect = image_tile(scene, t, tiles);
    SequenceRun run(path, base, shared, scene, budget_bytes, rect);
    while (!run.done()) {
      run.step(renderer);
      if (progress) progress((double(t) + run.progress()) / double(tiles));
    }
    add_tile(all, run.take(), rect, scene);
  }
  all.tiles = tiles;
  return all;
}

}  // namespace peakcast::distributed
