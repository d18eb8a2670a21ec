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

// render.clip (core/clip.h clip_span, its twin): the span cut to the crop box and to the kept
// side of the plane; empty when x > y.
vec2 clip_span(Ray r, vec2 span) {
  if (u_clip_lo.w > 0.5) {
    for (int a = 0; a < 3; ++a) {
      if (r.d[a] == 0.0) {
        if (r.o[a] < u_clip_lo[a] || r.o[a] > u_clip_hi[a]) return vec2(1.0, 0.0);
        continue;
      }
      float ta = (u_clip_lo[a] - r.o[a]) / r.d[a], tb = (u_clip_hi[a] - r.o[a]) / r.d[a];
      span.x = max(span.x, min(ta, tb));
      span.y = min(span.y, max(ta, tb));
    }
  }
  if (u_clip_hi.w > 0.5) {
    float dn = dot(u_clip_plane.xyz, r.d), on = dot(u_clip_plane.xyz, r.o) - u_clip_plane.w;
    if (dn > 0.0) span.x = max(span.x, -on / dn);
    else if (dn < 0.0) span.y = min(span.y, -on / dn);
    else if (on < 0.0) return vec2(1.0, 0.0);
  }
  return span;
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
