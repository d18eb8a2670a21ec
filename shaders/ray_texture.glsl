// Ray textures (Raspe & Müller 2008): per-ray controls read once, where the ray starts.
// Twin: server/core/ray_texture_mapping.h (the mappings) and the CPU reference.
//   .r step multiplier   (the ray's lattice is scaled by it)
//   .g termination       (early-termination opacity of this ray)
//   .b blend in [-1, 1]  (b > 0 fades the DVR samples' opacity by 1 - b, b < 0 the peaks' by 1 + b)
#ifdef RAY_TEXTURE
layout(binding = UNIT_RAY_TEXTURE) uniform sampler2D u_ray_texture;

// view: the pixel centre over the image (u right, v down); volume: the direction of the entry
// point from the box centre in box units (u around y from +z, v from the +y pole).
vec2 ray_texture_uv(Ray r, vec2 pixel, float t_enter) {
#ifdef RAY_TEXTURE_VOLUME
  const float pi = 3.14159265358979;
  vec3 n = (r.o + t_enter * r.d) / P.box_half;
  float len = length(n);
  if (!(len > 0.0)) return vec2(0.5);
  return vec2(0.5 + atan(n.x, n.z) / (2.0 * pi), acos(clamp(n.y / len, -1.0, 1.0)) / pi);
#else
  return pixel / vec2(P.image_width, P.image_height);
#endif
}

// Reads the controls into the ray's state and returns the step multiplier.
float read_ray_texture(Ray r, vec2 pixel, float t_enter, inout RayState s) {
  vec3 c = texture(u_ray_texture, ray_texture_uv(r, pixel, t_enter)).rgb;
  s.stop = c.g;
  s.dvr_weight = 1.0 - max(c.b, 0.0);
  s.peak_weight = 1.0 + min(c.b, 0.0);
  return c.r;
}
#endif
