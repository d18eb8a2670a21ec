#include "render/brick.h"

#include <stdexcept>
#include <string>

namespace peakcast::render {

void check_brick_scene(const ResolvedScene& s) {
  if (s.ray_texture) throw std::invalid_argument("distributed rendering: ray textures are not supported yet");
}

PixelRect check_brick_frame(const ResolvedScene& s, const Brick& brick, const glm::dvec3& spacing,
                            std::optional<PixelRect> tile) {
  check_brick_scene(s);
  for (int a = 0; a < 3; ++a) {
    const double whole = (s.box_max[a] - s.box_min[a]) / spacing[a];
    if (!(brick.own_lo[a] >= 0 && brick.own_lo[a] < brick.own_hi[a] && brick.own_hi[a] <= whole + 1e-9))
      throw std::invalid_argument("render_brick: the brick's box is not inside the scene's volume box");
  }
  const PixelRect rect = tile.value_or(PixelRect{0, 0, s.scene.width, s.scene.height});
  check_rect(rect, s.scene.width, s.scene.height);
  return rect;
}

void check_brick_variant(const VariantKey& key) {
  if (key.ray_texture)
    throw std::invalid_argument("distributed rendering: this frame's variant (" + key.name() +
                                ") reads a ray texture, which bricks do not draw yet");
}

}  // namespace peakcast::render
