// Fragment entry point of the ray caster: one fragment per pixel of an RGBA32F (or RGBA8UI,
// RGB8_OUTPUT) target, plus the sample count in a second R32F target.
#include "caster.glsl"

#ifdef RGB8_OUTPUT
layout(location = 0) out uvec4 out_color;
#else
layout(location = 0) out vec4 out_color;
#endif
layout(location = 1) out float out_samples;

void main() {
  // Target row k holds image row P.tile_y + k (row 0 at the top), so the read-back is already
  // in image order; (P.tile_x, P.tile_y) is the tile's first pixel (0, 0 for a full frame).
  vec2 pixel = vec2(P.tile_x, P.tile_y) + gl_FragCoord.xy;
  RayState res = cast_ray(pixel);
  out_color = output_color(res.acc);
  out_samples = res.samples;
}
