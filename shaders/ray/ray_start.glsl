// A ray from its pixel to the start of its walk, for both targets: the ray and its span (the box,
// then render.clip), its sample lattice, the ray texture's controls (Raspe & Müller 2008), the
// last lattice index, the walk's bookkeeping, a brick's share of the ray and the opacity the
// bricks in front composited. Reads the target's ray_texture_at (the texture's controls at uv)
// and front_opacity (that opacity at a pixel; < 0: none).

SHARED_CONST float kPi = 3.14159265358979f;

// Where a ray reads the ray texture (core/ray_texture_mapping.h is the reference's twin): view
// mapping, the pixel centre over the image (u right, v down); volume mapping, the direction of
// the entry point from the box centre in box units (u around y from +z, v from the +y pole).
vec2 ray_texture_uv(IN(Ray) r, vec2 pixel, float t_box) {
  if (!V.ray_texture_volume) return pixel / vec2(float(P.image_width), float(P.image_height));
  vec3 n = (r.o + t_box * r.d) / P.box_half;
  float len = length(n);
  if (!(len > 0.0f)) return vec2(0.5f);
  return vec2(0.5f + atan(n.x, n.z) / (2.0f * kPi), acos(clamp(n.y / len, -1.0f, 1.0f)) / kPi);
}

// The controls c: c.x the step multiplier (the lattice scaled by it), c.y the termination
// opacity, c.z the blend in [-1, 1] (c.z > 0 fades the DVR samples' opacity by 1 - c.z, c.z < 0
// the peaks' by 1 + c.z).
void apply_ray_texture(vec3 c, INOUT(Lattice) L, INOUT(RayState) s) {
  if (V.projection == kProjectionNone) s.stop = c.y;  // (a projection's opacity does not accumulate)
  s.dvr_weight = 1.0f - max(c.z, 0.0f);
  s.peak_weight = 1.0f + min(c.z, 0.0f);
  L.A *= c.x;
  L.B *= c.x;
}

// The ray through `pixel` (from the image's top-left corner) up to its walk; false when it draws
// nothing here (s.samples: -1 missed the box, or none of its points is this brick's, or the
// bricks in front stopped it; 0 the clip keeps none of it).
// On false only s is meaningful: the out parameters that follow the return are left unwritten
// (the callers read none of them then).
bool start_ray(vec2 pixel, OUT(Ray) r, OUT(Lattice) L, INOUT(RayState) s, OUT(RayWalk) k, OUT(vec2) span,
               OUT(int) last) {
  s.proj = projection_start();
  s.proj_len = 0.0f;
  r = make_ray(pixel);
  span = intersect_box(r);
  if (!(span.x <= span.y)) {  // missed (also false for NaN)
    s.samples = -1.0f;
    return false;
  }
  float t_box = span.x;  // the box entry: where a volume-mapped ray texture is read
  span = clip_span(r, span);
  if (!(span.x <= span.y)) {
    s.samples = 0.0f;
    return false;
  }
  L = ray_lattice(r, span.x);
  if (V.ray_texture) apply_ray_texture(ray_texture_at(ray_texture_uv(r, pixel, t_box)), L, s);
  last = int(min(floor(lattice_index(L, span.y)), float(P.sample_cap - 1)));
  k = start_walk(L, span.y, last);
  if (!V.brick) return true;
  if (!clip_to_brick(r, L, span, last, k.own_first, k.own_last)) {
    s.samples = -1.0f;
    return false;
  }
  float a = V.ray_texture ? front_opacity(pixel) : -1.0f;
  if (a >= 0.0f && a >= s.stop) {  // reached in front (after a consume there): one process stopped
    s.samples = -1.0f;
    return false;
  }
  if (a > 0.0f) s.stop = (s.stop - a) / (1.0f - a);  // a + (1 - a) * acc >= stop
  return true;
}
