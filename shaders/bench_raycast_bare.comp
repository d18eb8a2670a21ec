// peakcast-bench's compute entry point: raycast.comp's, with the bare sampling loop
// (bench_bare_sampling.glsl) in place of the ray caster. Never part of the product's programs.
#include "caster.glsl"
#include "bench_bare_sampling.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
#ifdef RGB8_OUTPUT
layout(rgba8ui, binding = IMAGE_COLOR) uniform writeonly uimage2D u_out_color;
#else
layout(rgba32f, binding = IMAGE_COLOR) uniform writeonly image2D u_out_color;
#endif
layout(r32f, binding = IMAGE_SAMPLES) uniform writeonly image2D u_out_samples;

void main() {
  ivec2 id = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(id, imageSize(u_out_color)))) return;
  vec2 pixel = vec2(ivec2(P.tile_x, P.tile_y) + id) + 0.5;
  RayState res = cast_ray_bare(pixel, id);
  imageStore(u_out_color, id, output_color(res.acc));
  imageStore(u_out_samples, id, vec4(res.samples));
}
