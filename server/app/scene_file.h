// Reading a scene file for the CLI: parse, then load its volume relative to the file.
#pragma once

#include <filesystem>
#include <memory>

#include "core/scene.h"
#include "core/volume.h"

namespace peakcast::app {

struct LoadedScene {
  std::shared_ptr<Volume> volume;
  ResolvedScene scene;
};

// Errors name the scene file: "scene.json: render.step: must be > 0".
LoadedScene load_scene_file(const std::filesystem::path& path);

// The scene file parsed (its ray-texture PNG read), and its volume's path resolved against the
// file's folder, without loading the volume: distributed ranks read only their bricks.
struct ParsedSceneFile {
  Scene scene;
  std::filesystem::path volume;
};
ParsedSceneFile parse_scene_file(const std::filesystem::path& path);

}  // namespace peakcast::app
