// Distributed rendering's glue between the k-d split and the renderers' brick frames: how
// many ghost voxels a scene needs, the brick as the renderer takes it, and the display rank's
// last step (the background under the composited layers). No MPI here: the tests composite
// bricks in one process with the same functions.
#pragma once

#include <vector>

#include "core/image.h"
#include "core/macrocell_share.h"
#include "core/scene.h"
#include "render/brick.h"
#include "distributed/kd_split.h"

namespace peakcast::distributed {

// Ghost voxels for a scene: the filter's support and shading's gradient (ghost_voxels), plus,
// for segment methods (preintegration, peak finding), the longest step (longest_step: a
// differential lattice's grows with depth): a rank samples the point one step before its first
// to draw the segment into it; virtual samples two steps (the Catmull-Rom window, both ways);
// adaptive sampling and a ray texture's step channel multiply the step by their largest
// multipliers.
int brick_ghost(const ResolvedScene& scene);

// A brick's share of the whole volume's macrocell grid (core/macrocell_share.h) over the voxels
// it counts (counted_box); `voxels` were read as the brick's region.
MacrocellShare brick_macrocell_share(const Volume& voxels, const Brick& brick, const Index3& dims,
                                     FilterSupport support);

// A bound on a ray texture's largest step multiplier (the ghosts hold that many steps): its PNG's
// largest, raised by its step strokes, at most kMaxStepMultiplier; 1 without a texture.
double max_step_multiplier(const RayTextureSpec* texture);

// Ray textures (render/brick.h Brick::front_opacity): the opacity over a brick's layer
// (premultiplied RGBA and samples per pixel) of the bricks in front of it (null: none), per
// pixel: what the brick behind it gets. -1 where no brick so far consumed a sample of the ray
// (a termination of 0 stops a ray after its first consume, wherever that is).
std::vector<float> opacity_over(const std::vector<float>* front, const Image& layer);

// The brick as Renderer::render_brick takes it; dims: the whole volume's.
render::Brick frame_brick(const Brick& brick, const Index3& dims);

// The front-to-back "over" of premultiplied RGBA layers (each width*height*4), in `order`:
// what IceT computes, for one process.
std::vector<float> composite_over(const std::vector<std::vector<float>>& layers, const std::vector<int>& order);

// The composited premultiplied layer over the scene's background: the image one process
// renders (rgb + (1 - a) background, a).
Image finish_composite(const std::vector<float>& rgba, int width, int height, const glm::dvec3& background);

}  // namespace peakcast::distributed
