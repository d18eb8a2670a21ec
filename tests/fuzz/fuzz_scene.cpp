// Any bytes as a scene file: parsed (and resolved against a small volume) or refused.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/generators.h"
#include "core/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const peakcast::Volume volume = [] {
    peakcast::GeneratorSpec g;
    g.dims = {4, 5, 6};
    return peakcast::generate_volume(g);
  }();
  try {
    auto scene = peakcast::parse_scene_text(std::string(reinterpret_cast<const char*>(data), size));
    peakcast::resolve_scene(scene, volume);
  } catch (const peakcast::SceneError&) {
  }
  return 0;
}
