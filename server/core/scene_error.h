// The one error type of scene and ray-texture parsing: its message names the key.
#pragma once

#include <stdexcept>

namespace peakcast {

class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace peakcast
