// Distributed rendering (docs/distributed.md): what one rank draws of a frame. The
// rank's resident volume holds one brick of a larger volume (read as a region, with ghosts);
// the scene is resolved against the whole volume (its box, camera and sample lattice). Every
// backend renders the brick's part of each ray: premultiplied RGBA, transparent where the ray
// owns no lattice point here, no background (the compositor puts it under the ranks' layers),
// rays running until opaque: no rank sees the opacity in front of its brick, except with a ray
// texture, whose per-ray early termination needs it (Brick::front_opacity).
#pragma once

#include <glm/vec3.hpp>

#include <memory>
#include <optional>
#include <vector>

#include "core/scene.h"
#include "core/volume.h"
#include "render/frame.h"
#include "render/variant.h"

namespace peakcast::render {

struct Brick {
  glm::dvec3 read_lo{0};            // the resident voxel 0 in the whole volume's voxels
  glm::dvec3 own_lo{0}, own_hi{0};  // the owned box, whole-volume voxel coordinates
  // own_lo is the volume's first voxel, own_hi its last, on that axis: no bound there (every
  // lattice point lies in the volume's box; rounding may put the first or last a hair outside).
  bool at_start[3] = {false, false, false}, at_end[3] = {false, false, false};
  // Ray textures: the opacity the bricks in front of this one composited, per pixel of the
  // drawn rect (row-major); null for the front brick. A ray whose front opacity reaches its
  // termination draws nothing here, the others stop where their opacity over it reaches it.
  std::shared_ptr<const std::vector<float>> front_opacity;
};

// render_brick's checks before anything is drawn (std::invalid_argument): the brick's own box
// inside the scene's volume box, the tile inside the image, the front opacity one value per
// pixel of it. Returns the pixels to draw (`tile`, or the whole image). A brick's resident
// volume carries the whole volume's macrocell grids (core/macrocell_share.h), so cell walks
// (space skipping, adaptive multipliers, where a virtual-sample run ends) visit the points one
// process visits: every scene one process draws, bricks draw, but projections (check_bricks_draw).
PixelRect check_brick_frame(const ResolvedScene& scene, const Brick& brick, const glm::dvec3& spacing,
                            std::optional<PixelRect> tile);
// What bricks cannot draw yet, refused (SceneError naming the key) before any brick is read or
// any rank asked: projections (a brick's layer is composited front to back; a projection needs
// the values' maximum, minimum or mean across bricks).
void check_bricks_draw(const ResolvedScene& scene);

}  // namespace peakcast::render
