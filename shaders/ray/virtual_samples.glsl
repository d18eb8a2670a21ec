// Virtual samples (Lee et al. 2010, §3.1, §4): between consecutive true samples j and j+1, k more
// (V.virtual_samples = 3 or 7) on the Catmull-Rom spline through the true samples j-1..j+2 (in
// index space; at a run's ends the end sample is repeated), gradients likewise; each of the k+1
// sub-samples stands for 1/(k+1) of the step. One new true sample per step: the true samples
// wait in a window of four (SampleWindow) and go out one step late, with the virtual ones that
// follow them. t_entry: the ray's first lattice point (its sample stands for half a sub-step).

SHARED_CONST float kNoLimit = 3.0e38f;

// A window sample's ownership (bricks; one process owns every sample).
bool window_owns(uint own, uint bit) { return !V.brick || (own & bit) != 0u; }

// Sends out the true sample at t1 (value f.y, step dt1) and the virtual samples between it and
// the next one (t2) that lie before t_limit, on the spline through f.x..f.w (g0..g3).
bool vs_segment(IN(Ray) r, INOUT(RayState) s, float t_entry, float t1, float t2, float dt1, vec4 f, vec3 g0, vec3 g1,
                vec3 g2, vec3 g3, float t_limit, bool own) {
  s.draw = own;  // the segment's samples are the rank's that owns its first
  float k = float(V.virtual_samples);
  float sub = dt1 / (k + 1.0f);
  float span = t2 - t1;
  // The sub-samples' chords as the true samples' (lattice.glsl chord_at_ends), on the
  // sub-lattice: the ray's first sample stands for half a sub-step, and the last before the exit
  // (t_limit: the ray's last segment) for half a sub-step before it and the rest up to the exit.
  // (The true sample outside the loop: llvmpipe's budget of loop iterations, P.sample_cap,
  // counts k per true sample.)
  bool ends = t_limit < kNoLimit;
  float weight = sub;
  if (t1 == t_entry) weight -= 0.5f * sub;
  if (ends && t1 + span / (k + 1.0f) > t_limit) weight += (t_limit - t1) - 0.5f * sub;
  if (consume(r, s, t1, f.y, g1, weight)) return true;
  for (int q = 1; q <= V.virtual_samples; ++q) {
    float a = float(q) / (k + 1.0f);
    float t = t1 + a * span;
    if (t > t_limit) break;
    weight = sub;
    if (ends && (q == V.virtual_samples || t1 + float(q + 1) / (k + 1.0f) * span > t_limit))
      weight += (t_limit - t) - 0.5f * sub;
    float v = catmull_rom(f.x, f.y, f.z, f.w, a);
    vec3 g = catmull_rom3(g0, g1, g2, g3, a);
    if (consume(r, s, t, v, g, weight)) return true;
  }
  return false;
}

// The segment between the two newest samples (.z, .w), the spline's end: p3 repeats .w, p0 is .y
// when there is one.
bool vs_last_segment(IN(Ray) r, INOUT(RayState) s, INOUT(SampleWindow) w, float t_entry, float t_limit) {
  bool prev = w.n >= 3;
  return vs_segment(r, s, t_entry, w.t.z, w.t.w, w.dt.z, vec4(prev ? w.f.y : w.f.z, w.f.z, w.f.w, w.f.w),
                    prev ? w.g1 : w.g2, w.g2, w.g3, w.g3, t_limit, window_owns(w.own, 2u));
}

// Everything still waiting: the last true sample stands for its whole step.
bool vs_flush(IN(Ray) r, INOUT(RayState) s, INOUT(SampleWindow) w, float t_entry) {
  bool done = s.acc.w >= s.stop;
  if (!done && w.n >= 2) done = vs_last_segment(r, s, w, t_entry, kNoLimit);
  if (!done && w.n >= 1) {
    s.draw = window_owns(w.own, 1u);
    done = consume(r, s, w.t.w, w.f.w, w.g3, w.dt.w);
  }
  w.n = 0;
  return done;
}

// A new true sample at t (value f, gradient g, step dt); the segment before the newest goes out
// once it is known: with samples j-1, j, j+1, j+2 (or j, j+1, j+2 at a run's start), j..j+1.
bool vs_push(IN(Ray) r, INOUT(RayState) s, INOUT(SampleWindow) w, float t_entry, float t, float f, vec3 g, float dt,
             bool own) {
  w.own = ((w.own << 1u) | (own ? 1u : 0u)) & 15u;
  w.t = vec4(w.t.y, w.t.z, w.t.w, t);
  w.f = vec4(w.f.y, w.f.z, w.f.w, f);
  w.dt = vec4(w.dt.y, w.dt.z, w.dt.w, dt);
  w.g0 = w.g1;
  w.g1 = w.g2;
  w.g2 = w.g3;
  w.g3 = g;
  w.n = min(w.n + 1, 4);
  if (w.n < 3) return false;
  bool prev = w.n == 4;
  return vs_segment(r, s, t_entry, w.t.y, w.t.z, w.dt.y, vec4(prev ? w.f.x : w.f.y, w.f.y, w.f.z, w.f.w),
                    prev ? w.g0 : w.g1, w.g1, w.g2, w.g3, kNoLimit, window_owns(w.own, 4u));
}

// The ray's end. When its last lattice point was visited, one more true sample past the exit
// (index last + 1, read by the target's lattice_field) closes the spline, and the virtual samples
// up to the exit go out: the ray ends like a ray sampled at the sub-step would (its last sample
// within one sub-step of the exit), not one whole step beyond it.
void vs_finish(IN(Ray) r, INOUT(RayState) s, INOUT(SampleWindow) w, IN(Lattice) L, int last, int own_last, float t_exit) {
  if (s.acc.w >= s.stop || w.n == 0) return;
  if (w.t.w != lattice_t(L, float(last))) {  // the ray ended in a skipped cell
    vs_flush(r, s, w, L.t0);
    return;
  }
  float t = lattice_t(L, float(last + 1));
  float f = lattice_field(r, L, last + 1, 1);
  s.samples += 1.0f;
  vec3 g = V.shading ? field_gradient(r, voxel_at(r, t)) : vec3(0.0f);
  if (vs_push(r, s, w, L.t0, t, f, g, lattice_step(L, float(last + 1), 1.0f), last + 1 <= own_last)) return;
  vs_last_segment(r, s, w, L.t0, t_exit);  // pending now: [..., last, last + 1]; the extra sample is not composited
  w.n = 0;
}
