// Opacity correction and front-to-back emission-absorption compositing (docs/scenes.md): colour
// not premultiplied in the TF; a preintegrated segment's colour is.

// The TF table's fourth channel is the transparency T of the uniform step (`step`, the ray's
// copy of P.step): a sample
// standing for that step has opacity 1 - T (no pow), any other step (a ray's first and last
// samples, differential, adaptive, virtual samples, ray textures) corrects from it:
// 1 - T^(dt / step). A transparency keeps a near-opaque step's precision (1 - T may round to 1).
float step_opacity(float T, float dt, float step) {
  return dt == step ? 1.0f - T : 1.0f - pow(max(T, 0.0f), dt / step);
}

// A preintegrated segment of the table's step (premultiplied, opacity c.w > 0) for a segment of
// length len: its opacity corrected, its colour scaled with it.
vec4 segment_for_length(vec4 c, float len, float step) {
  float a = 1.0f - pow(max(1.0f - c.w, 0.0f), len / step);
  return vec4(vec3(c) * (a / c.w), a);
}

void composite(INOUT(vec4) acc, vec3 rgb, float alpha) {
  float w = (1.0f - acc.w) * alpha;
  acc += vec4(w * rgb, w);
}

// A premultiplied colour and opacity (a preintegrated segment), weighted.
void composite_premultiplied(INOUT(vec4) acc, vec4 c, float weight) { acc += (1.0f - acc.w) * weight * c; }

vec3 finish_pixel(vec4 acc) { return vec3(acc) + (1.0f - acc.w) * P.background; }
