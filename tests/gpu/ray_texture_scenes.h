// What the ray-texture tests share: Marschner-Lobb 41^3 and a TF over its [0, 1] range with a
// smooth band and a near-Dirac peak at 0.7 (so the blend channel has peaks to fade).
#pragma once

#include <memory>

#include "gpu/gpu_fixture.h"

namespace peakcast::test {

inline std::shared_ptr<Volume> ray_texture_volume() {
  return make_volume(GeneratorKind::MarschnerLobb, {41, 41, 41}, SourceType::F32);
}

inline const nlohmann::json kRayTextureTf = {
    {"points",
     {{0.0, 0.1, 0.2, 0.8, 0.0}, {0.45, 0.3, 0.6, 0.9, 0.05}, {0.6, 0.9, 0.6, 0.3, 0.35}, {1.0, 1.0, 1.0, 1.0, 0.0}}}};

}  // namespace peakcast::test
