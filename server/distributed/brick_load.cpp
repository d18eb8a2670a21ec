#include "distributed/brick_load.h"

#include <mpi.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/macrocell_share.h"
#include "core/volume_io.h"

namespace peakcast::distributed {
namespace {

// The whole volume's macrocell grid of a filter support, reduced from every rank's share
// (core/macrocell_share.h): each rank then walks the cells one process walks.
std::shared_ptr<const MacrocellGrid> reduce_grid(const Volume& v, const Brick& mine, const Index3& dims,
                                                 FilterSupport support) {
  const auto [lo, hi] = counted_box(mine, dims);
  MacrocellShare s = macrocell_share(v, dims, lo, hi, support);
  const int n = int(s.min.size());
  MPI_Allreduce(MPI_IN_PLACE, s.min.data(), n, MPI_FLOAT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, s.max.data(), n, MPI_FLOAT, MPI_MAX, MPI_COMM_WORLD);
  for (std::vector<double>* sums : {&s.own, &s.sum, &s.sum2})
    MPI_Allreduce(MPI_IN_PLACE, sums->data(), n, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  return std::make_shared<const MacrocellGrid>(grid_from_share(s));
}

// This rank's brick of the request's file (its time point) with its ghosts, NaN/Inf kept: they
// take the whole volume's finite extremes, as in one process.
std::shared_ptr<Volume> read_own_brick(const BrickLoadRequest& req, const Brick& mine) {
  LoadOptions region;
  region.region = VoxelRegion{mine.read_lo, mine.read_hi};
  region.time_point = req.time_point;
  region.nonfinite = NonFinitePolicy::Keep;
  return std::make_shared<Volume>(load_volume(req.path, region));
}

}  // namespace

nlohmann::json BrickLoadRequest::to_json() const {
  nlohmann::json j = {{"path", path}, {"time", time_point}, {"ghost", ghost}, {"refuse_nonfinite", refuse_nonfinite}};
  if (have_range) {
    j["lo"] = lo;
    j["hi"] = hi;
  }
  return j;
}

BrickLoadRequest BrickLoadRequest::from_json(const nlohmann::json& j) {
  BrickLoadRequest r;
  r.path = j.at("path");
  r.time_point = j.value("time", int64_t(0));
  r.ghost = j.at("ghost");
  r.refuse_nonfinite = j.value("refuse_nonfinite", false);
  if (j.contains("lo")) {
    r.have_range = true;
    r.lo = j.at("lo");
    r.hi = j.at("hi");
  }
  return r;
}

Volume read_head(const std::string& path, int64_t time_point) {
  LoadOptions one;
  one.region = VoxelRegion{{0, 0, 0}, {1, 1, 1}};
  one.time_point = time_point;
  return load_volume(path, one);
}

namespace {

// The whole volume's histogram and its faces' histogram (the automatic TF's background), each
// rank counting its own box and the sums going to every rank.
void reduce_histograms(Volume& v, const Brick& mine, const Index3& dims, double lo, double hi) {
  const auto [own_lo, own_hi] = counted_box(mine, dims);
  v.histogram = v.box_histogram(own_lo, own_hi, lo - v.value_offset, hi - v.value_offset);
  MPI_Allreduce(MPI_IN_PLACE, v.histogram.data(), int(v.histogram.size()), MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
  const auto [face_lo, face_hi] = whole_faces(mine, dims);
  v.border_histogram =
      v.box_border_histogram(own_lo, own_hi, face_lo, face_hi, lo - v.value_offset, hi - v.value_offset);
  MPI_Allreduce(MPI_IN_PLACE, v.border_histogram.data(), int(v.border_histogram.size()), MPI_UINT64_T, MPI_SUM,
                MPI_COMM_WORLD);
}

}  // namespace

BrickRead read_brick(const BrickLoadRequest& req) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  BrickRead b;
  b.ghost = req.ghost;
  std::shared_ptr<Volume> v;
  glm::dvec3 spacing{1.0}, origin{0.0};
  // A rank that cannot read its part (a damaged compressed stream past the header, a file its
  // node does not see) says so in the first collective: every rank then returns `failed`
  // alike, and the job goes on.
  int failed_rank = 0;  // rank + 1 of a rank that failed; the highest such
  try {
    const Volume head = read_head(req.path, req.time_point);
    spacing = head.spacing;
    origin = head.origin;
    b.dims = {head.source_dims[0], head.source_dims[1], head.source_dims[2]};
    b.split = kd_split(b.dims, size, b.ghost);
    b.mine = b.split.bricks[size_t(rank)];
    v = read_own_brick(req, b.mine);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "peakcast: rank %d of %d cannot read its brick: %s\n", rank, size, e.what());
    std::fflush(stderr);
    b.error = e.what();
    failed_rank = rank + 1;
  }
  MPI_Allreduce(MPI_IN_PLACE, &failed_rank, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (failed_rank > 0) {
    b.failed = true;
    if (b.error.empty())
      b.error = req.path + ": rank " + std::to_string(failed_rank - 1) + " cannot read its brick (its log says why)";
    return b;
  }
  const auto t_stats = std::chrono::steady_clock::now();
  double lo = req.lo, hi = req.hi;
  if (!req.have_range) {
    const auto [own_lo, own_hi] = counted_box(b.mine, b.dims);
    int64_t nonfinite = count_nonfinite(*v, own_lo, own_hi);
    MPI_Allreduce(MPI_IN_PLACE, &nonfinite, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    b.nonfinite = nonfinite;
    if (nonfinite > 0 && req.refuse_nonfinite) {
      b.refused = true;
      return b;
    }
    float f_lo = std::numeric_limits<float>::infinity(), f_hi = -f_lo;
    if (v->type() == VoxelType::F32) std::tie(f_lo, f_hi) = finite_extremes(*v);
    MPI_Allreduce(MPI_IN_PLACE, &f_lo, 1, MPI_FLOAT, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &f_hi, 1, MPI_FLOAT, MPI_MAX, MPI_COMM_WORLD);
    // Also where the rank's own box has none: its ghosts may (another brick counts them).
    // Nothing finite anywhere: 0. A brick without any keeps the statistics the read computed.
    replace_nonfinite(*v, f_lo <= f_hi ? f_lo : 0.f, f_lo <= f_hi ? f_hi : 0.f);
    lo = v->min_value;
    hi = v->max_value;
    MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    int64_t bytes = int64_t(v->byte_size());
    MPI_Allreduce(MPI_IN_PLACE, &bytes, 1, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD);
    b.max_brick_bytes = bytes;
  } else {
    replace_nonfinite(*v, float(lo - v->value_offset), float(hi - v->value_offset));
  }
  v->min_value = lo;
  v->max_value = hi;
  // Every rank's brick carries the whole volume's histogram (adaptive sampling's volume
  // standard deviation) and macrocell grids.
  reduce_histograms(*v, b.mine, b.dims, lo, hi);
  if (!req.have_range) b.histogram = v->histogram;
  if (!req.have_range) b.border_histogram = v->border_histogram;
  b.cells.trilinear = reduce_grid(*v, b.mine, b.dims, FilterSupport::Trilinear);
  b.cells.tricubic = reduce_grid(*v, b.mine, b.dims, FilterSupport::Tricubic);
  b.statistics_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t_stats).count();
  b.box = VolumeBox{b.dims, spacing, origin, lo, hi, v->histogram, v->border_histogram};
  b.voxels = std::move(v);
  return b;
}

}  // namespace peakcast::distributed
