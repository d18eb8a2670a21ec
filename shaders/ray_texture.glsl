// GL's hooks for the ray's start (ray/ray_start.glsl): the ray texture (Raspe & Müller 2008) as a
// texture, read with GL_LINEAR between texel centres, clamped at the edges (.r step multiplier,
// .g termination, .b blend), and on a brick the opacity the bricks in front composited, per pixel
// of the drawn rect (rows of P.front_opacity_width pixels; 0: the front brick, none). Declared in
// every variant: one without ray textures folds the calls away.
layout(binding = UNIT_RAY_TEXTURE) uniform sampler2D u_ray_texture;

vec3 ray_texture_at(vec2 uv) { return texture(u_ray_texture, uv).rgb; }

#if defined(BRICK) && defined(RAY_TEXTURE)
layout(std430, binding = SSBO_FRONT_OPACITY) readonly buffer FrontOpacity { float u_front_opacity[]; };
float front_opacity(vec2 pixel) {
  if (P.front_opacity_width <= 0) return -1.0;
  ivec2 p = ivec2(pixel) - ivec2(P.tile_x, P.tile_y);
  return u_front_opacity[p.y * P.front_opacity_width + p.x];
}
#else
float front_opacity(vec2 pixel) { return -1.0; }
#endif
