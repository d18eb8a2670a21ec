// Serving under MPI (docs/distributed.md): a session's ray texture reaches the workers inside
// the render commands that use it. A texture new to them goes whole (mapping, size, a PNG's
// texels as CBOR binary, its strokes); after that only the strokes painted since the last
// command, so a brush stroke costs the broadcast of one stroke, and each worker keeps one spec
// per texture whose edit lineage stays the same (its renderer then applies only the new strokes,
// as one process's does). Both sides keep the same kKept textures, dropping the oldest alike.
// No MPI here: the commands carry the JSON.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>

#include <nlohmann/json.hpp>

#include "core/ray_texture.h"

namespace peakcast::distributed {

constexpr size_t kKeptRayTextures = 16;

// Rank 0.
class RayTextureSender {
 public:
  // What a render command carries for `spec`, and counts it as sent.
  nlohmann::json message(const RayTextureSpec& spec);

 private:
  std::map<uint64_t, size_t> sent_;  // rank 0's lineage -> strokes the workers hold
  std::deque<uint64_t> order_;
};

// The other ranks.
class RayTextureReceiver {
 public:
  // The spec the message describes. std::runtime_error when it continues a texture this rank
  // does not hold at the stroke count it names (the ranks fell out of step).
  std::shared_ptr<const RayTextureSpec> apply(const nlohmann::json& message);

 private:
  std::map<uint64_t, std::shared_ptr<const RayTextureSpec>> specs_;  // by rank 0's lineage
  std::deque<uint64_t> order_;
};

}  // namespace peakcast::distributed
