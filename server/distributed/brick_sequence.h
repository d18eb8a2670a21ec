// Out-of-core rendering: the brick path of a distributed render taken in time by one process
// (docs/chunked-volumes.md). The volume is cut into the fewest k-d bricks that fit a host memory
// budget; the whole volume's statistics are reduced from the bricks as the ranks reduce them, and
// a still is drawn brick after brick, front to back, each layer composited "over" as it comes,
// the next brick read while this one renders. Any format with region reads works: OME-Zarr and
// Neuroglancer precomputed read only the chunks a brick meets.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/macrocell_share.h"
#include "core/macrocells.h"
#include "core/scene.h"
#include "core/volume_io.h"
#include "distributed/kd_split.h"
#include "render/renderer.h"

namespace peakcast::distributed {

// The fewest bricks whose largest read box (ghosts included) holds at most `budget_bytes` of
// voxels; `holding` bricks are held at once (2: one rendering, the next being read). Throws
// std::invalid_argument when even one voxel plane per brick would not fit.
int bricks_for_budget(const Index3& dims, int ghost, size_t voxel_bytes, int64_t budget_bytes, int holding);

struct SequenceStatistics {
  VolumeBox box;           // dims, spacing, origin, the whole volume's range and histogram
  VolumeMacrocells cells;  // the whole volume's grids, from the bricks' shares
  SourceType source = SourceType::U8;
  int64_t nonfinite = 0;  // NaN/Inf voxels, replaced by the finite extremes
  int bricks = 0;
  int64_t bytes_read = 0;  // voxel bytes of both passes
  double ms = 0.0;
  // What the statistics hold beside each brick (the grids' shares, the value counts) left the
  // bricks less than half their share of the budget: they got that half, over the budget.
  bool budget_too_small = false;
};

// The bricks of a sequence take 90% of budget_bytes; the rest is for decoding chunks, the image
// layers and the grids. Statistics: integer volumes in one pass over the bricks (each stored
// value counted: range and histogram exactly, and the macrocell shares); float volumes in two,
// the finite range, then the histogram and the macrocell grids over that range. `base` carries level, time point,
// channel and the non-finite policy (Refuse throws VolumeError as a whole read would). The same, one brick read at a
// time (a server's render thread steps it between viewers' frames).
class StatisticsRun {
 public:
  StatisticsRun(std::string path, LoadOptions base, int64_t budget_bytes);  // reads the header
  ~StatisticsRun();
  void step();  // the next brick; throws VolumeError as a whole read would
  bool done() const;
  double progress() const;    // share of the brick reads done
  SequenceStatistics take();  // once done

 private:
  int total_steps() const;
  void add_shares(const Volume& v, size_t k);
  void finish();
  std::string path_;
  LoadOptions base_;
  std::chrono::steady_clock::time_point t0_;
  SequenceStatistics s_;
  Index3 dims_{};
  KdSplit split_;
  bool floats_ = false;
  double offset_ = 0.0;
  int steps_ = 0;
  MacrocellShare shares_[2];
  std::vector<uint64_t> counts_, histogram_, border_counts_, border_histogram_;  // (border_: the faces' voxels)
  double lo_ = std::numeric_limits<double>::infinity(), hi_ = -std::numeric_limits<double>::infinity();
};

SequenceStatistics sequence_statistics(const std::string& path, const LoadOptions& base, int64_t budget_bytes,
                                       const std::function<void(double)>& progress = {});

struct SequenceResult {
  Image image;
  int bricks = 0, ghost = 0;
  int tiles = 1;  // bands of rows drawn one after another, each over every brick (image_tiles)
  int64_t bytes_read = 0;
  int64_t largest_brick_bytes = 0;
  double read_ms = 0.0, render_ms = 0.0;  // reading overlaps rendering: the two add up to more than the wall time
  // The image's buffers and the grids (beside_bytes) leave the bricks less than half their share
  // of the budget: the bricks get that half, and the still holds more than the budget.
  int64_t beside_bytes = 0;
  bool budget_too_small = false;
};

// The bands of rows a still by bricks is drawn in: the fewest whose image buffers (eight RGBA
// float images of a band: the layers, the composite, the renderer's) take at most a quarter of
// the budget, so that the bricks keep most of it (a 1024² still under 256 MiB: 2 bands; each band
// reads every brick again). A budget that would need more than kMaxImageTiles bands (a 512² still
// under 1 MiB: 128) is drawn in one, and says it held more than the budget (budget_too_small),
// rather than read its bricks a hundred times: banding is for images whose buffers are up to
// the budget itself.
inline constexpr int kMaxImageTiles = 4;
int image_tiles(const ResolvedScene& scene, int64_t budget_bytes);
// Band t of `tiles`: rows [t h / tiles, (t + 1) h / tiles).
render::PixelRect image_tile(const ResolvedScene& scene, int t, int tiles);

// One band's result into the whole still's (its image placed at `rect`, the counts added).
void add_tile(SequenceResult& all, SequenceResult tile, const render::PixelRect& rect, const ResolvedScene& scene);

// `scene` (resolved against stats.box) drawn by bricks with `renderer`, holding at most two
// bricks (90% of budget_bytes in all), in image_tiles bands. progress: the share of bricks
// composited.
SequenceResult render_sequence(render::Renderer& renderer, const std::string& path, const LoadOptions& base,
                               const SequenceStatistics& stats, const ResolvedScene& scene, int64_t budget_bytes,
                               const std::function<void(double)>& progress = {});

// The same, one brick at a time: step() composites the next brick (the one after it is read
// meanwhile). A server's render thread steps it between viewers' frames.
class SequenceRun {
 public:
  // `rect`: the pixels drawn (a band of image_tiles); default the whole image. take()'s image is
  // the rect's.
  SequenceRun(std::string path, LoadOptions base, std::shared_ptr<const SequenceStatistics> stats, ResolvedScene scene,
              int64_t budget_bytes, std::optional<render::PixelRect> rect = std::nullopt);
  ~SequenceRun();  // waits for a read in flight
  SequenceRun(const SequenceRun&) = delete;
  SequenceRun& operator=(const SequenceRun&) = delete;
  void step(render::Renderer& renderer);
  bool done() const;
  double progress() const;  // share of the bricks composited
  int bricks() const { return r_.bricks; }
  SequenceResult take();  // once done

 private:
  struct Read {
    std::shared_ptr<Volume> voxels;
    double ms = 0.0;
  };
  std::future<Read> read_ahead(int k);
  std::string path_;
  LoadOptions base_;
  std::shared_ptr<const SequenceStatistics> stats_;
  ResolvedScene scene_;
  render::PixelRect rect_;
  KdSplit split_;
  std::vector<int> order_;
  size_t next_brick_ = 0;
  std::vector<float> acc_;
  std::shared_ptr<const std::vector<float>> front_;
  std::future<Read> next_;
  SequenceResult r_;
};

}  // namespace peakcast::distributed
