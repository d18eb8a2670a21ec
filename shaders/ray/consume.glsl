// The step every sample of a ray takes, true or virtual (consume): the peaks in the segment from
// the previous sample, then the sample itself (post-classified by the TF table, or the
// pre-integrated segment into it), composited front to back. Reads the target's tf_lookup and
// preint_lookup (false, leaving the colour alone, where the table is exactly zero there) and
// field_gradient.

// The gradient a sample is shaded with: interpolated like the value for a virtual sample (Lee
// §4: g), else central differences at the sample.
vec3 sample_gradient(IN(Ray) r, float t, vec3 g) {
  return V.virtual_samples != 0 ? g : field_gradient(r, voxel_at(r, t));
}

// One sample at t with value f (TF coordinates), standing for the step dt, with gradient g
// (virtual samples). True when the ray is opaque enough to stop.
bool consume(IN(Ray) r, INOUT(RayState) s, float t, float f, vec3 g, float dt) {
  if (V.projection != kProjectionNone) return project_sample(s, f, dt);  // (one process: no brick draws a projection)
  bool segment = s.have_prev && !s.gap;
  bool draw = !V.brick || s.draw;  // a brick draws only the points it owns
  float dvr_weight = V.ray_texture ? s.dvr_weight : 1.0f;  // (folded where no ray texture can change it)
  bool peak_hit = false;
  if (V.peaks && segment) peak_hit = find_peaks(r, s, s.prev_t, s.prev_f, t, f);
  if (V.preintegration) {
    vec4 c;
    if (segment && draw && preint_lookup(r, s.prev_f, f, c)) {
      // The table holds segments of the uniform step: correct for this one's length.
      bool varying_steps = V.differential || V.adaptive || V.virtual_samples != 0;
      if (varying_steps && c.w > 0.0f) c = segment_for_length(c, t - s.prev_t, r.step);
      if (V.shading) {
        // at the segment's end, as preintegration does
        if (c.w > 0.0f) composite(s.acc, shade(r, vec3(c) / c.w, sample_gradient(r, t, g)), c.w * dvr_weight);
      } else {
        composite_premultiplied(s.acc, c, dvr_weight);  // opacity-weighted already: no divide
      }
    }
  } else if (draw && !(V.peaks && (V.peaks_only || (V.peak_xor && peak_hit)))) {
    vec4 c;  // .w: the uniform step's transparency
    if (tf_lookup(f, c) && c.w < 1.0f) {
      float alpha = step_opacity(c.w, dt, r.step) * dvr_weight;
      vec3 rgb = vec3(c);
      if (V.shading) rgb = shade(r, rgb, sample_gradient(r, t, g));
      composite(s.acc, rgb, alpha);
    }
  }
  s.prev_t = t;
  s.prev_f = f;
  s.have_prev = true;
  s.gap = false;
  return draw && s.acc.w >= s.stop;
}

// The segment from the last lattice point visited to the exit (preintegration without virtual
// samples): the table's segments cover the chord between samples, this the rest of the ray.
// Drawn by the rank owning that point, when the ray goes on there (`continues`: the walk's last
// visit was the ray's last lattice point, without a gap).
void close_segment(IN(Ray) r, INOUT(RayState) s, float t_exit, bool continues) {
  if (!(s.have_prev && !s.gap && (!V.brick || s.draw) && continues && s.acc.w < s.stop)) return;
  vec3 x = voxel_at(r, t_exit);
  float f = sample_field(r, x);
  s.samples += 1.0f;
  vec4 c;
  if (!preint_lookup(r, s.prev_f, f, c) || !(c.w > 0.0f)) return;
  c = segment_for_length(c, t_exit - s.prev_t, r.step);
  if (!(c.w > 0.0f)) return;  // an exit on (or a hair past) the last point: nothing left (and no 0 / 0)
  float dvr_weight = V.ray_texture ? s.dvr_weight : 1.0f;
  if (V.shading) {
    composite(s.acc, shade(r, vec3(c) / c.w, field_gradient(r, x)), c.w * dvr_weight);
  } else {
    composite_premultiplied(s.acc, c, dvr_weight);
  }
}
