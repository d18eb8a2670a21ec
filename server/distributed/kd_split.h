// Distributed rendering: the volume cut into one brick per MPI rank by a k-d split,
// and the order in which the ranks' images composite (front to back for a camera).
//
// Bricks are boxes in voxel coordinates (voxel i at coordinate i; the volume's box runs from 0 to
// dims-1, docs/scenes.md). Neighbouring bricks share their boundary plane, which lies on a voxel
// centre; a ray sample exactly on it belongs to exactly one brick (the ray caster takes the
// half-open parameter interval [t_enter, t_exit) of each brick). A brick reads its box plus
// `ghost` voxels on every inner side, for the reconstruction filter's support.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

namespace peakcast::distributed {

using Index3 = std::array<int64_t, 3>;

struct Brick {
  int rank = 0;
  Index3 lo{}, hi{};            // the owned box in voxel coordinates, lo < hi on every axis
  Index3 read_lo{}, read_hi{};  // the voxels to read: [read_lo, read_hi), the box plus ghosts
  int64_t voxels_read() const {
    return (read_hi[0] - read_lo[0]) * (read_hi[1] - read_lo[1]) * (read_hi[2] - read_lo[2]);
  }
  std::string to_string() const;
};

// The k-d tree: each inner node splits its box at a voxel plane along one axis.
struct KdNode {
  int axis = -1;      // -1: a leaf holding `rank`
  int64_t plane = 0;  // voxel coordinate of the split
  int rank = -1;
  std::unique_ptr<KdNode> below, above;  // coordinates < plane, > plane
};

struct KdSplit {
  std::vector<Brick> bricks;  // indexed by rank
  std::unique_ptr<KdNode> root;
};

// Ghost voxels a filter needs beyond a brick's box: the filter's support plus one for the
// central-difference gradient of shading. trilinear 1 (+1), tricubic 2 (+1); Catmull-Rom virtual
// samples read the true samples' neighbours, which lie inside the tricubic/trilinear support.
int ghost_voxels(bool tricubic, bool shading);

// Splits dims among `ranks` bricks (any count >= 1, uneven allowed): the longest axis first,
// each side getting a share of the voxel planes proportional to its share of ranks. Throws
// std::invalid_argument when the volume has fewer cells than ranks along every axis it could cut.
KdSplit kd_split(const Index3& dims, int ranks, int ghost);

// The voxels `brick` alone counts when the bricks' statistics are summed: its box's half-open
// [lo, hi), closed on the volume's upper faces (a plane two bricks share is counted by the brick
// above it), in the coordinates of the brick's read voxels (from read_lo). The bricks' boxes
// tile the volume's voxels exactly once.
std::pair<Index3, Index3> counted_box(const Brick& brick, const Index3& dims);

// The whole volume's first and last voxel planes along each axis, in the coordinates of the
// brick's read voxels (Volume::for_each_border_voxel: the faces a brick's statistics count).
std::pair<Index3, Index3> whole_faces(const Brick& brick, const Index3& dims);

// The ranks front to back as seen from the camera, in voxel coordinates: the eye's position
// for a perspective camera, the view direction for an orthographic one.
std::vector<int> visibility_order(const KdSplit& split, const glm::dvec3& eye_voxel, const glm::dvec3& view_dir,
                                  bool orthographic);

}  // namespace peakcast::distributed
