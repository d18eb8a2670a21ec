// Compute entry point of the ray caster: 8x8 pixels per work group, same body as the fragment
// path; writes bottom-up like the fragment path so one read-back serves both.
#include "uniforms.glsl"
#include "ray_setup.glsl"
#include "common_sampling.glsl"
#include "tf.glsl"
#include "compositing.glsl"
#include "shading.glsl"
#include "raycast_body.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) uniform writeonly image2D u_out_color;
layout(r32f, binding = 1) uniform writeonly image2D u_out_samples;

void main() {
  ivec2 id = ivec2(gl_GlobalInvocationID.xy);
  if (id.x >= u_image.x || id.y >= u_image.y) return;
  vec2 pixel = vec2(id) + 0.5;  // id.y counts rows from the top
  ivec2 store = ivec2(id.x, u_image.y - 1 - id.y);
  RayResult res = CAST_RAY(pixel, store);
  imageStore(u_out_color, store, vec4(finish_pixel(res.acc), res.acc.a));
  imageStore(u_out_samples, store, vec4(res.samples));
}
