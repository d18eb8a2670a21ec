#include "render/brick.h"

#include <stdexcept>
#include <string>

#include "core/scene_error.h"

namespace peakcast::render {

void check_bricks_draw(const ResolvedScene& s) {
  if (is_projection(s.scene.render.classification))
    throw SceneError(std::string("render.classification ") + to_string(s.scene.render.classification) +
                     ": projections are not drawn by bricks yet (MPI ranks, or a volume larger than memory at "
                     "full resolution); render a pyramid level that fits, or use post, preint or peaks");
}

PixelRect check_brick_frame(const ResolvedScene& s, const Brick& brick, const glm::dvec3& spacing,
                            std::optional<PixelRect> tile) {
  check_bricks_draw(s);
  for (int a = 0; a < 3; ++a) {
    const double whole = (s.box_max[a] - s.box_min[a]) / spacing[a];
    if (!(brick.own_lo[a] >= 0 && brick.own_lo[a] < brick.own_hi[a] && brick.own_hi[a] <= whole + 1e-9))
      throw std::invalid_argument("render_brick: the brick's box is not inside the scene's volume box");
  }
  const PixelRect rect = tile.value_or(PixelRect{0, 0, s.scene.width, s.scene.height});
  check_rect(rect, s.scene.width, s.scene.height);
  if (brick.front_opacity && brick.front_opacity->size() != size_t(rect.w) * size_t(rect.h))
    throw std::invalid_argument("render_brick: the front opacity holds " + std::to_string(brick.front_opacity->size()) +
                                " values for " + std::to_string(rect.w) + "x" + std::to_string(rect.h) + " pixels");
  return rect;
}

}  // namespace peakcast::render
