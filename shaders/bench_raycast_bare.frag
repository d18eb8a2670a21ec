// peakcast-bench's fragment entry point: raycast.frag's, with the bare sampling loop
// (bench_bare_sampling.glsl) in place of the ray caster. Never part of the product's programs.
#include "caster.glsl"
#include "bench_bare_sampling.glsl"

#ifdef RGB8_OUTPUT
layout(location = 0) out uvec4 out_color;
#else
layout(location = 0) out vec4 out_color;
#endif
layout(location = 1) out float out_samples;

void main() {
  vec2 pixel = vec2(P.tile_x, P.tile_y) + gl_FragCoord.xy;
  RayState res = cast_ray_bare(pixel, ivec2(gl_FragCoord.xy));
  out_color = output_color(res.acc);
  out_samples = res.samples;
}
