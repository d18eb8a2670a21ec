// Fragment entry point of the ray caster: one fragment per pixel of an RGBA32F target, plus
// the sample count in a second R32F target.
#include "uniforms.glsl"
#include "ray_setup.glsl"
#include "common_sampling.glsl"
#include "tf.glsl"
#include "compositing.glsl"
#include "shading.glsl"
#include "raycast_body.glsl"

layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_samples;

void main() {
  // gl_FragCoord.y counts from the bottom; the ray generator counts rows from the top.
  vec2 pixel = vec2(gl_FragCoord.x, float(u_image.y) - gl_FragCoord.y);
  RayResult res = CAST_RAY(pixel, ivec2(gl_FragCoord.xy));
  out_color = vec4(finish_pixel(res.acc), res.acc.a);
  out_samples = res.samples;
}
