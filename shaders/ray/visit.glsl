// One visit of the walk: lattice index i, standing for the step to index i + m. The sample is
// read by the target's lattice_field, then consumed (consume.glsl) or, with virtual samples,
// pushed into the window (virtual_samples.glsl). True when the ray is opaque enough to stop.

// The walk's start, once the ray's last lattice index is known: every point owned (one
// process; clip_to_brick narrows it on a brick) and the chord corrections at the ray's ends.
RayWalk start_walk(IN(Lattice) L, float t_exit, int last) {
  RayWalk k;
  k.expect = 0;
  k.own_first = 0;
  k.own_last = 2147483647;
  k.ray_last = last;
  k.head = chord_head(L);
  k.tail = chord_tail(L, t_exit, last);
  k.behind = ivec4(-1, -1, 1, 1);
  return k;
}

RAY_INLINE bool sample_visit(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int i, int m) {
  // The sample's chord; with virtual samples the true step (vs_segment cuts the sub-samples').
  float dt = lattice_step(L, float(i), float(m));
  if (V.virtual_samples == 0 && (i == 0 || i + m > k.ray_last)) dt = chord_at_ends(dt, i, m, k.head, k.tail, k.ray_last);
  float t = lattice_t(L, float(i));
  float f = lattice_field(r, L, i, m);
  s.samples += 1.0f;
  bool own = i >= k.own_first && i <= k.own_last;
  s.draw = own;
  bool gap = i != k.expect;  // lattice points between the last visit and this one were skipped
  k.expect = i + m;
  if (gap) s.gap = true;  // until the next sample is consumed: no segment across the gap
  if (V.virtual_samples != 0) {
    if (gap && w.n > 0) {  // the run before the gap ends here
      s.gap = false;       // (its samples are contiguous among themselves)
      if (vs_flush(r, s, w, L.t0)) return true;
      s.gap = true;
    }
    vec3 g = V.shading ? field_gradient(r, voxel_at(r, t)) : vec3(0.0f);
    return vs_push(r, s, w, L.t0, t, f, g, dt, own);  // (vs_flush may have drawn another's)
  }
  return consume(r, s, t, f, vec3(0.0f), dt);
}

// A brick's visit before its points (held back in k.behind), or its first owned visit with
// visits held back: those that lead to it without a gap are visited first.
RAY_COLD bool visit_behind(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int i, int m) {
  if (i < k.own_first) {
    k.behind = ivec4(i, k.behind.x, m, k.behind.z);
    return false;
  }
  ivec4 b = k.behind;
  k.behind = ivec4(-1, -1, 1, 1);
  if (b.x + b.z == i) {
    if (V.virtual_samples != 0 && b.y >= 0 && b.y + b.w == b.x && sample_visit(r, L, s, k, w, b.y, b.w)) return true;
    if (sample_visit(r, L, s, k, w, b.x, b.z)) return true;
  }
  return sample_visit(r, L, s, k, w, i, m);
}

RAY_INLINE bool visit(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int i, int m) {
  if (V.brick && (i < k.own_first || k.behind.x >= 0)) return visit_behind(r, L, s, k, w, i, m);
  return sample_visit(r, L, s, k, w, i, m);
}
