#include "distributed/kd_split.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace peakcast::distributed {

std::string Brick::to_string() const {
  std::ostringstream s;
  s << "rank " << rank << ": [" << lo[0] << "," << hi[0] << "]x[" << lo[1] << "," << hi[1] << "]x[" << lo[2] << ","
    << hi[2] << "], reads " << voxels_read() << " voxels";
  return s.str();
}

int ghost_voxels(bool tricubic, bool shading) { return (tricubic ? 2 : 1) + (shading ? 1 : 0); }

namespace {

std::unique_ptr<KdNode> split(Index3 lo, Index3 hi, int ranks, int first_rank, std::vector<Brick>& out) {
  auto node = std::make_unique<KdNode>();
  if (ranks == 1) {
    node->rank = first_rank;
    out[first_rank].rank = first_rank;
    out[first_rank].lo = lo;
    out[first_rank].hi = hi;
    return node;
  }
  // The longest axis that has room for a plane strictly inside.
  int axis = -1;
  for (int a = 0; a < 3; ++a)
    if (hi[a] - lo[a] >= 2 && (axis < 0 || hi[a] - lo[a] > hi[axis] - lo[axis])) axis = a;
  if (axis < 0)
    throw std::invalid_argument("cannot split a brick of " + std::to_string(hi[0] - lo[0]) + "x" +
                                std::to_string(hi[1] - lo[1]) + "x" + std::to_string(hi[2] - lo[2]) + " cells among " +
                                std::to_string(ranks) + " ranks: too few voxels");
  const int below = ranks / 2, above = ranks - below;
  const int64_t cells = hi[axis] - lo[axis];
  int64_t plane = lo[axis] + (cells * below + ranks / 2) / ranks;
  plane = std::clamp(plane, lo[axis] + 1, hi[axis] - 1);
  node->axis = axis;
  node->plane = plane;
  Index3 mid_hi = hi, mid_lo = lo;
  mid_hi[axis] = plane;
  mid_lo[axis] = plane;
  node->below = split(lo, mid_hi, below, first_rank, out);
  node->above = split(mid_lo, hi, above, first_rank + below, out);
  return node;
}

void order(const KdNode* n, const glm::dvec3& eye, const glm::dvec3& dir, bool ortho, std::vector<int>& out) {
  if (n->axis < 0) {
    out.push_back(n->rank);
    return;
  }
  // The side holding the eye (perspective) or facing the viewer (orthographic) comes first.
  const bool below_first = ortho ? dir[n->axis] > 0 : eye[n->axis] < double(n->plane);
  order(below_first ? n->below.get() : n->above.get(), eye, dir, ortho, out);
  order(below_first ? n->above.get() : n->below.get(), eye, dir, ortho, out);
}

}  // namespace

KdSplit kd_split(const Index3& dims, int ranks, int ghost) {
  if (ranks < 1) throw std::invalid_argument("ranks must be >= 1");
  for (int a = 0; a < 3; ++a)
    if (dims[a] < 1) throw std::invalid_argument("volume dims must be >= 1");
  KdSplit s;
  s.bricks.resize(size_t(ranks));
  const Index3 hi{dims[0] - 1, dims[1] - 1, dims[2] - 1};
  s.root = split({0, 0, 0}, hi, ranks, 0, s.bricks);
  for (Brick& b : s.bricks)
    for (int a = 0; a < 3; ++a) {
      b.read_lo[a] = std::max<int64_t>(0, b.lo[a] - ghost);
      b.read_hi[a] = std::min<int64_t>(dims[a], b.hi[a] + 1 + ghost);
    }
  return s;
}

std::vector<int> visibility_order(const KdSplit& split, const glm::dvec3& eye_voxel, const glm::dvec3& view_dir,
                                  bool orthographic) {
  std::vector<int> out;
  order(split.root.get(), eye_voxel, view_dir, orthographic, out);
  return out;
}

std::pair<Index3, Index3> counted_box(const Brick& b, const Index3& dims) {
  Index3 lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    lo[a] = b.lo[a] - b.read_lo[a];
    hi[a] = b.hi[a] - b.read_lo[a] + (b.hi[a] == dims[a] - 1 ? 1 : 0);
  }
  return {lo, hi};
}

std::pair<Index3, Index3> whole_faces(const Brick& b, const Index3& dims) {
  Index3 lo{}, hi{};
  for (int a = 0; a < 3; ++a) {
    lo[a] = -b.read_lo[a];
    hi[a] = dims[a] - 1 - b.read_lo[a];
  }
  return {lo, hi};
}

}  // namespace peakcast::distributed
