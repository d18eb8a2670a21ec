// The binding points and encodings the ray-cast shaders share with the host (like the uniform
// block, shaders/ray/uniforms.glsl): one definition here, handed to every shader as #defines by
// interface_defines(), so GLSL never carries a bare unit number (shaders/README.md lists them).
#pragma once

#include <string>
#include <vector>

namespace peakcast::render {

// Texture units (sampler bindings).
constexpr unsigned kUnitVolume = 0;      // sampler3D: the scalar volume
constexpr unsigned kUnitTf = 1;          // sampler1D: the baked TF table
constexpr unsigned kUnitPeakTable = 4;   // sampler2DArray: peak values per (f_front, f_back) bin
constexpr unsigned kUnitPreint = 5;      // sampler2D: preintegration table
constexpr unsigned kUnitRayTexture = 7;  // sampler2D: ray texture (step, termination, blend)
// Image units (compute path outputs).
constexpr unsigned kImageColor = 0;
constexpr unsigned kImageSamples = 1;
// Buffer bindings.
constexpr unsigned kUboRay = 0;        // std140 RayUniforms
constexpr unsigned kSsboTfPoints = 0;  // TF points for the peak root solve
// One byte per macrocell, four to a uint, grid order (make_cell_buffer). Buffers, not integer
// 3D textures: on llvmpipe a texelFetch cost ~30 of a 40 ms blobs frame's traversal, a buffer
// load a fraction of that.
constexpr unsigned kSsboCellDistance = 1;  // cells to the nearest occupied macrocell (0: occupied)
constexpr unsigned kSsboCellStride = 2;    // adaptive step multiplier per macrocell
constexpr unsigned kSsboFrontOpacity = 3;  // BRICK + RAY_TEXTURE: the opacity in front, per pixel of the rect
constexpr unsigned kSsboCellRange = 4;     // maximum/minimum projections: (min, max) per macrocell, TF coordinates

// A peak-table texel with no peak. Peak values are TF coordinates in [0, 1], so any negative
// value is free; the CPU table's own sentinel is PeakTable::kNoPeak (data units, unbounded).
constexpr float kNoPeakTexel = -1.0f;

// "NAME value" pairs for the shader preamble.
std::vector<std::string> interface_defines();

}  // namespace peakcast::render
