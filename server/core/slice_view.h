// A 2D slice of a volume, as POST /api/slice draws it (docs/rest.md, "Slices"): an axis-aligned
// slice (x, y or z at a voxel index) or an oblique plane, seen as the 3D view sees the volume
// from the slice normal's positive side, nearest-voxel values through the TF's colours (opacity
// ignored) or a grey window.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

#include "core/scene.h"
#include "core/volume.h"

namespace peakcast {

struct SliceRequest {
  int axis = -1;      // 0 x, 1 y, 2 z; -1: the plane below
  int64_t index = 0;  // along the axis, in the volume's full-resolution voxels (level 0 of a pyramid)
  glm::dvec3 point{0.0}, normal{0.0, 0.0, 1.0};  // a plane, world units
  std::optional<std::array<double, 2>> window;   // grey from lo (black) to hi (white) instead of the TF
};
// {"axis": "x"|"y"|"z", "index": k} or {"plane": {"point": [..], "normal": [..]}}, and optional
// "window": [lo, hi]. Throws SceneError naming the key.
SliceRequest parse_slice(const nlohmann::json& j);

struct SliceImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // row 0 at the top
  int64_t index = -1;        // an axis slice: the index in the voxels drawn (a coarser level's)
};

// Draws the slice of `v` (the voxels held: a pyramid's level that fits) for the resolved scene:
// its TF (the colours), background, camera up (default +y, or +z for a y slice). `size`: the
// image to fill (the slice fitted into it, its world aspect kept); none: one pixel per voxel (an
// oblique plane: per smallest spacing). Throws SceneError for an index outside the volume or a
// normal of zero length.
SliceImage draw_slice(const Volume& v, const ResolvedScene& r, const SliceRequest& s,
                      std::optional<std::array<int, 2>> size);

}  // namespace peakcast
