// Intensity projections (classifications mip, minip, average; docs/scenes.md): instead of
// compositing, a ray keeps the maximum, the minimum or the chord-weighted mean of its samples'
// values (true and virtual, on the lattice of its span; the TF does not decide which cells matter,
// so TF space skipping does not apply, but a maximum or minimum skips the cells whose values
// cannot change it: below), and its pixel is the TF at that value, composited once:
// colour c.rgb and opacity c.a, the TF's own opacity (no step correction), over the background.
// Reads tf_exact (ray/peaks.glsl).

SHARED_CONST int kProjectionNone = 0;
SHARED_CONST int kProjectionMax = 1;
SHARED_CONST int kProjectionMin = 2;
SHARED_CONST int kProjectionMean = 3;

// What a ray has projected before its first sample: nothing (below every value for a maximum,
// above for a minimum; a mean's empty sum).
float projection_start() {
  if (V.projection == kProjectionMax) return -kHuge;
  if (V.projection == kProjectionMin) return kHuge;
  return 0.0f;
}

// A maximum or a minimum skips the macrocells that cannot change it (walks.glsl walk_cells): a
// cell whose values (over its filter's support: cell_range, the target's hook, in TF
// coordinates, widened by 1e-5) all lie at or below the maximum so far, or at or above the
// minimum. Exact up to float rounding, as a cell's samples are convex blends of those values
// (a cell whose top equals the maximum so far is still walked: the widening); not with virtual
// samples (the spline overshoots, and the window would lose its neighbours). A mean takes every
// sample.
bool projection_skips() { return (V.projection == kProjectionMax || V.projection == kProjectionMin) && V.virtual_samples == 0; }
bool projection_may_change(IN(RayState) s, vec2 range) {
  return V.projection == kProjectionMax ? range.y > s.proj : range.x < s.proj;
}

// One sample of value f (TF coordinates) standing for the chord dt (a mean's weight; a maximum
// or minimum reads no chord). True when no later sample
// can change the result: a maximum at the top of the TF's domain, a minimum at its bottom (the
// volume's value range: trilinear and B-spline samples stay inside it; Catmull-Rom virtual
// samples may overshoot, so then the ray goes on).
bool project_sample(INOUT(RayState) s, float f, float dt) {
  if (V.projection == kProjectionMean) {
    s.proj_len += dt;
    s.proj += f * dt;
    return false;
  }
  s.proj = V.projection == kProjectionMax ? max(s.proj, f) : min(s.proj, f);
  if (V.virtual_samples != 0) return false;
  return V.projection == kProjectionMax ? s.proj >= 1.0f : s.proj <= 0.0f;
}

// The ray's end: the TF at the projected value, composited (a ray texture's blend weighs its
// opacity as a DVR sample's). A ray without samples, or a mean over chords of no length, adds
// nothing.
void finish_projection(INOUT(RayState) s) {
  float v = s.proj;
  if (V.projection == kProjectionMean) {
    if (!(s.proj_len > 0.0f)) return;
    v = s.proj / s.proj_len;
  } else if (!(abs(v) < kHuge)) {
    return;
  }
  vec4 c = tf_exact(v);
  composite(s.acc, vec3(c), c.w * (V.ray_texture ? s.dvr_weight : 1.0f));
}
