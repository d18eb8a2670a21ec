// Ray generation, the ray-box slab test, render.clip, and where a point's voxels are
// (docs/scenes.md). A pixel's ray goes through its centre; row 0 is the top row.

SHARED_CONST float kHuge = 3.0e38f;

// The ray o + t d (t_eye: the eye's t) with the frame's values its samples read.
Ray ray_from(vec3 o, vec3 d, float t_eye) {
  Ray r;
  r.o = o;
  r.d = d;
  r.t_eye = t_eye;
  r.voxel_half = P.sample_half;
  r.inv_spacing = P.inv_spacing;
  r.spacing = P.spacing;
  r.inv_dims = P.inv_dims;
  r.value_scale = P.value_scale;
  r.value_bias = P.value_bias;
  r.step = P.step;
  r.min_spacing = P.min_spacing;
  r.peak_bins = P.peak_bins;
  r.preint_size = P.preint_size;
  return r;
}

Ray make_ray(vec2 pixel_from_top_left) {
  float nx = pixel_from_top_left.x / float(P.image_width) * 2.0f - 1.0f;
  float ny = 1.0f - pixel_from_top_left.y / float(P.image_height) * 2.0f;
  vec3 lateral = nx * P.half_width * P.right + ny * P.half_height * P.up;
  if (V.orthographic) return ray_from(P.p0 + lateral, P.forward, -P.eye_distance);
  vec3 d = P.forward + lateral;  // depth 1 along the view axis
  float len = length(d);
  return ray_from(P.p0 + P.eye_distance * lateral, d / len, -P.eye_distance * len);
}

// Slab test against the box [-half, half]; returns (t_enter, t_exit), empty when x > y.
vec2 intersect_box(IN(Ray) r) {
  // Axis-parallel rays: a tiny stand-in for 0 keeps every product finite (no 0 * inf = NaN).
  vec3 d = mix(r.d, vec3(1e-20f), lessThan(abs(r.d), vec3(1e-20f)));
  vec3 inv = 1.0f / d;
  vec3 t0 = (-P.box_half - r.o) * inv;
  vec3 t1 = (P.box_half - r.o) * inv;
  vec3 tmin = min(t0, t1), tmax = max(t0, t1);
  float enter = max(max(tmin.x, tmin.y), tmin.z);
  float exit_ = min(min(tmax.x, tmax.y), tmax.z);
  return vec2(max(enter, r.t_eye), exit_);
}

// render.clip (core/clip.h): the span cut to the crop box and to the kept side of the plane;
// empty when x > y.
vec2 clip_span(IN(Ray) r, vec2 span) {
  if (P.clip_box != 0) {
    for (int a = 0; a < 3; ++a) {
      if (r.d[a] == 0.0f) {
        if (r.o[a] < P.clip_lo[a] || r.o[a] > P.clip_hi[a]) return vec2(1.0f, 0.0f);
        continue;
      }
      float ta = (P.clip_lo[a] - r.o[a]) / r.d[a], tb = (P.clip_hi[a] - r.o[a]) / r.d[a];
      span.x = max(span.x, min(ta, tb));
      span.y = min(span.y, max(ta, tb));
    }
  }
  if (P.clip_plane != 0) {
    float dn = dot(P.clip_normal, r.d), on = dot(P.clip_normal, r.o) - P.clip_offset;
    if (dn > 0.0f) span.x = max(span.x, -on / dn);
    else if (dn < 0.0f) span.y = min(span.y, -on / dn);
    else if (on < 0.0f) return vec2(1.0f, 0.0f);
  }
  return span;
}

// Where the ray's point at t lies in the resident voxels (voxel i at i); a brick's are moved by
// its first voxel (P.sample_half).
vec3 voxel_at(IN(Ray) r, float t) { return (r.o + t * r.d + r.voxel_half) * r.inv_spacing; }
// Where the macrocells are looked up: the whole volume's voxel coordinates (a brick's grids are
// the whole volume's, core/macrocell_share.h); voxel_at in one process.
vec3 cell_coords(vec3 p) { return (p + P.box_half) * P.inv_spacing; }
