// Any bytes as a ray-texture PNG (render.ray_texture.png) read through OpenImageIO: a texture
// within the size limit or a SceneError naming the key, never a crash or a big allocation; a
// texture that loads takes a stroke. Seeds: tests/fuzz/seeds/fuzz_ray_texture_png (8 and 16
// bit, with alpha, grey, wrong sizes).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/ray_texture_png.h"
#include "core/scene_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace peakcast;
  static const std::filesystem::path file = [] {
    auto d = std::filesystem::temp_directory_path() / ("peakcast_fuzz_rtpng_" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d / "paint.png";
  }();
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), std::streamsize(size));
  try {
    const auto image = read_ray_texture_png(file);
    RayTexture t(*image);
    Stroke s;
    s.radius = 0.5;
    s.level = 2;
    t.apply(s);
  } catch (const SceneError&) {
  }
  return 0;
}
