#include "app/scene_file.h"

#include <fstream>
#include <sstream>

#include "core/ray_texture_png.h"
#include "core/volume_io.h"
#include "render/variant.h"

namespace fs = std::filesystem;

namespace peakcast::app {

ParsedSceneFile parse_scene_file(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open scene file");
  std::stringstream text;
  text << in.rdbuf();
  Scene scene;
  try {
    scene = parse_scene_text(text.str());
  } catch (const SceneError& e) {
    throw SceneError(path.string() + ": " + e.what());
  }
  // A ray-texture PNG, like the volume, is found relative to the scene file.
  const PngLocator beside_scene = [&](const std::string& png) {
    fs::path p = png;
    return p.is_relative() ? path.parent_path() / p : p;
  };
  try {
    scene.render.ray_texture = load_ray_texture_png(scene.render.ray_texture, beside_scene);
  } catch (const SceneError& e) {
    throw SceneError(path.string() + ": " + e.what());
  }
  fs::path vol = scene.volume;
  if (vol.is_relative()) vol = path.parent_path() / vol;
  return {std::move(scene), vol};
}

LoadedScene load_scene_file(const fs::path& path) {
  ParsedSceneFile parsed = parse_scene_file(path);
  LoadedScene out;
  LoadOptions options;
  options.time_point = parsed.scene.time;  // a time series' (resolve_scene refuses it for a volume without)
  out.volume = std::make_shared<Volume>(load_volume(parsed.volume, options));
  try {
    out.scene = resolve_scene(parsed.scene, *out.volume);
  } catch (const SceneError& e) {
    throw SceneError(path.string() + ": " + e.what());
  }
  return out;
}

}  // namespace peakcast::app
