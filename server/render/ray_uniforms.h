// The ray caster's uniforms (shaders/ray/uniforms.glsl, one definition for GLSL and C++), filled
// from a scene the same way for both backends: the GL ray caster uploads them as its uniform
// block, the CPU backend's rays read them. No GL here.
#pragma once

#include "ray/cxx_prelude.h"
#include "core/macrocells.h"
#include "core/scene.h"
#include "core/volume.h"
#include "render/brick.h"
#include "render/frame.h"
#include "render/variant.h"

#include <map>
#include <string>

namespace peakcast::ray {
#include "ray/uniforms.glsl"
#include "ray/variant.glsl"
static_assert(sizeof(RayUniforms) % 16 == 0, "std140 rows");
}  // namespace peakcast::ray

namespace peakcast::render {

// The sizes of the per-TF tables a frame reads (zero where the variant reads none).
struct TableShape {
  int peak_bins = 0, peak_layers = 0, preint_size = 0, tf_point_count = 0;
};

// The texels' map to TF coordinates: a * texel + b.
struct ValueMap {
  float scale = 1.f, bias = 0.f;
};

// `resident`: the voxels a backend holds (a brick's, in distributed rendering, with `brick` set).
ray::RayUniforms make_ray_uniforms(const ResolvedScene& s, const Volume& resident, ValueMap map,
                                   const MacrocellGrid& cells, const TableShape& tables, const PixelRect& rect,
                                   int sample_cap, const Brick* brick);

ray::Variant shared_variant(const VariantKey& key);

// Member name (as GL reports it, "RayUniforms.name") -> byte offset, for the layout test.
std::map<std::string, size_t> host_uniform_offsets();

}  // namespace peakcast::render
