// Ray generation and ray-box intersection (docs/scenes.md). A pixel's ray goes through its centre;
// row 0 is the top row. The ray is written o + t*d with o near the box (not at the eye), so t
// stays small even for a camera 1e6 away; t_eye is the eye's own parameter (rays start there).
struct Ray {
  vec3 o;
  vec3 d;
  float t_eye;
};

Ray make_ray(vec2 pixel_from_top_left) {
  vec2 ndc = vec2(pixel_from_top_left.x / float(u_image.x) * 2.0 - 1.0,
                  1.0 - pixel_from_top_left.y / float(u_image.y) * 2.0);
  vec3 lateral = ndc.x * u_right.w * u_right.xyz + ndc.y * u_up.w * u_up.xyz;
  Ray r;
#ifdef ORTHOGRAPHIC
  r.o = u_p0.xyz + lateral;
  r.d = u_forward.xyz;
  r.t_eye = -u_forward.w;
#else
  vec3 d = u_forward.xyz + lateral;  // depth 1 along the view axis
  float len = length(d);
  r.o = u_p0.xyz + u_forward.w * lateral;
  r.d = d / len;
  r.t_eye = -u_forward.w * len;
#endif
  return r;
}

// Slab test against the box [-half, half]; returns (t_enter, t_exit), empty when x > y.
vec2 intersect_box(Ray r) {
  // Axis-parallel rays: a tiny stand-in for 0 keeps every product finite (no 0 * inf = NaN).
  vec3 d = mix(r.d, vec3(1e-20), lessThan(abs(r.d), vec3(1e-20)));
  vec3 inv = 1.0 / d;
  vec3 t0 = (-u_box_half.xyz - r.o) * inv;
  vec3 t1 = (u_box_half.xyz - r.o) * inv;
  vec3 tmin = min(t0, t1), tmax = max(t0, t1);
  float enter = max(max(tmin.x, tmin.y), tmin.z);
  float exit_ = min(min(tmax.x, tmax.y), tmax.z);
  return vec2(max(enter, r.t_eye), exit_);
}
