#include "core/vessel_tree.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "core/hash.h"

namespace peakcast {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kGenerations = 6;
constexpr double kEdge = 0.55;  // width of the lumen's edge (logistic), voxels

glm::dvec3 rotate(const glm::dvec3& v, const glm::dvec3& axis, double angle) {  // Rodrigues
  return v * std::cos(angle) + glm::cross(axis, v) * std::sin(angle) +
         axis * glm::dot(axis, v) * (1.0 - std::cos(angle));
}

struct Grower {
  uint64_t seed;
  glm::dvec3 to_voxels;  // normalised [0, 1]^3 -> voxel coordinates
  double radius0;
  VesselTree& tree;
  int next_id = 0;

  double rnd(int id, int what) const { return hash01(seed, id, what, 0, 0x7e55e1); }

  // A tube from p (normalised coordinates) along unit dir, then two daughters.
  void grow(const glm::dvec3& p, const glm::dvec3& dir, double len, double radius, int generation) {
    const int id = next_id++;
    const glm::dvec3 q = p + dir * len;
    tree.tubes.push_back({p * to_voxels, q * to_voxels, std::max(radius, 0.7)});
    if (generation == 0) {  // the aneurysm sits on the first bifurcation, off to one side
      const glm::dvec3 side = glm::normalize(glm::cross(dir, glm::dvec3(0.3, 0.2, 1.0)));
      tree.sac_radius = std::max(2.2 * radius, 1.0);
      tree.sac_center = q * to_voxels + side * (1.1 * radius);
    }
    if (generation + 1 >= kGenerations) return;
    // Branch plane: a random direction perpendicular to the parent; daughters on either side.
    const glm::dvec3 helper = std::abs(dir.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::dvec3 e1 = glm::normalize(glm::cross(dir, helper)), e2 = glm::cross(dir, e1);
    const double phi = 2.0 * kPi * rnd(id, 1);
    const glm::dvec3 axis = std::cos(phi) * e1 + std::sin(phi) * e2;
    for (int side = 0; side < 2; ++side) {
      const double angle = (side ? -1.0 : 1.0) * (25.0 + 15.0 * rnd(id, 2 + side)) * kPi / 180.0;
      const double shrink = 0.72 + 0.14 * rnd(id, 4 + side);
      grow(q, glm::normalize(rotate(dir, axis, angle)), len * shrink, radius * 0.79, generation + 1);  // Murray
    }
  }
};

double segment_distance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double s = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + s * ab));
}

}  // namespace

VesselTree make_vessel_tree(uint64_t seed, const Dims& dims) {
  VesselTree tree;
  tree.seed = seed;
  const glm::dvec3 to_voxels(double(std::max<int64_t>(dims[0] - 1, 1)), double(std::max<int64_t>(dims[1] - 1, 1)),
                             double(std::max<int64_t>(dims[2] - 1, 1)));
  const double smallest = std::min({to_voxels.x, to_voxels.y, to_voxels.z});
  Grower g{seed, to_voxels, 0.045 * smallest, tree};
  const glm::dvec3 root(0.5 + 0.1 * (hash01(seed, 0, 0, 1) - 0.5), 0.03, 0.5 + 0.1 * (hash01(seed, 0, 0, 2) - 0.5));
  const glm::dvec3 dir = glm::normalize(glm::dvec3(hash01(seed, 0, 0, 3) - 0.5, 2.5, hash01(seed, 0, 0, 4) - 0.5));
  g.grow(root, dir, 0.3, g.radius0, 0);
  return tree;
}

double VesselTree::value(int64_t i, int64_t j, int64_t k) const {
  const glm::dvec3 p{double(i), double(j), double(k)};
  double sd = glm::length(p - sac_center) - sac_radius;  // signed distance to the lumen
  for (const auto& t : tubes) sd = std::min(sd, segment_distance(p, t.a, t.b) - t.radius);
  const double tissue = 0.1 + 0.03 * (hash01(seed, i, j, k, 0x715) - 0.5);
  const double lumen = 1.0 / (1.0 + std::exp(std::clamp(sd / kEdge, -60.0, 60.0)));
  return tissue + (0.92 - tissue) * lumen;
}

}  // namespace peakcast
