// Compute entry point of the ray caster: 8x8 pixels per work group, same body as the fragment
// path; the target holds the tile's rows top-down like the fragment path, so one read-back
// serves both.
#include "caster.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
#ifdef RGB8_OUTPUT
layout(rgba8ui, binding = IMAGE_COLOR) uniform writeonly uimage2D u_out_color;
#else
layout(rgba32f, binding = IMAGE_COLOR) uniform writeonly image2D u_out_color;
#endif
layout(r32f, binding = IMAGE_SAMPLES) uniform writeonly image2D u_out_samples;

void main() {
  ivec2 id = ivec2(gl_GlobalInvocationID.xy);  // in the tile, rows from the top
  if (any(greaterThanEqual(id, imageSize(u_out_color)))) return;
  vec2 pixel = vec2(ivec2(P.tile_x, P.tile_y) + id) + 0.5;
  RayState res = cast_ray(pixel);
  imageStore(u_out_color, id, output_color(res.acc));
  imageStore(u_out_samples, id, vec4(res.samples));
}
