// Ray textures from and to PNG files (render.ray_texture.png). Channels, 8 or 16 bit, with
// M = 255 or 65535 and the midpoint h = (M + 1) / 2 (128 or 32768):
//   R  step multiplier     8^((R - h) / h):  h is x1 exactly, 0 is x1/8, M is x8^(1 - 1/h)
//   G  termination         G / M:            254 of 255 is the default 1 - 1/255, M is 1
//   B  blend               (B - h) / h:      h is 0 exactly, 0 is -1 (peaks faded out)
// A PNG with an alpha channel has it ignored; grey and palette PNGs are refused (they do not
// carry three channels). Side 1..kMaxRayTextureSide.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "core/ray_texture.h"

namespace peakcast {

// Throws SceneError naming `key` (e.g. "render.ray_texture.png") and the file.
std::shared_ptr<const RayTextureImage> read_ray_texture_png(const std::filesystem::path& path,
                                                            const std::string& key = "render.ray_texture.png");
// 8-bit RGB PNG of a texture's channels (the inverse of read_ray_texture_png, to 8 bits).
void write_ray_texture_png(const RayTexture& texture, const std::filesystem::path& path);

// Where a spec's png lives: the CLI resolves it beside the scene file, the server inside its
// data directories (resolve_in_roots). Throws on a path it refuses.
using PngLocator = std::function<std::filesystem::path(const std::string& png)>;

// The spec with its PNG read (the same spec when it names none, or has it read already).
std::shared_ptr<const RayTextureSpec> load_ray_texture_png(const std::shared_ptr<const RayTextureSpec>& spec,
                                                           const PngLocator& locate);

}  // namespace peakcast
