// Ray textures on bricks (render/brick.h Brick::front_opacity): a ray's early termination is of
// the opacity over every brick in front of the point it reaches, so the ranks draw one after
// another in visibility order, each handing the rank behind it the opacity over its layer. Only
// frames with a ray texture pay this: N renders in turn instead of side by side, and one float
// image passed N - 1 times. MPI point-to-point on MPI_COMM_WORLD (IceT works on its own copy).
#pragma once

#include <memory>
#include <vector>

#include "core/image.h"

namespace peakcast::distributed {

// `order`: the ranks front to back. The opacity in front of this rank's brick, per pixel of the
// drawn rect (`pixels` of them): null for the front rank, else received from the rank before it
// in the order (blocks until that rank has drawn).
std::shared_ptr<const std::vector<float>> receive_front_opacity(const std::vector<int>& order, size_t pixels);
// Hands the opacity over this rank's layer (`front` as received; distributed/brick_frame.h
// opacity_over) to the rank behind it; nothing for the back rank.
void send_opacity_behind(const std::vector<int>& order, const std::vector<float>* front, const Image& layer);

}  // namespace peakcast::distributed
