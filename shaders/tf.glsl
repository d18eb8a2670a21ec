// Transfer-function lookup (8192-entry table over the volume's value range, sampled at texel
// centres: colour, and the transparency of the scene's uniform step, baked by the host) and the
// opacity of the step actually taken (docs/scenes.md).
layout(binding = UNIT_TF) uniform sampler1D u_tf;

vec4 tf_lookup(float s) {
  float size = u_value_map.z;
  return texture(u_tf, clamp(s, 0.0, 1.0) * ((size - 1.0) / size) + 0.5 / size);
}

// The table's fourth channel is the transparency T of the uniform step (u_box_half.w): a sample
// standing for that step has opacity 1 - T (no pow), any other step (a ray's first and last
// samples, differential, adaptive, virtual samples, ray textures) corrects from it:
// 1 - T^(dt / step). A transparency keeps a near-opaque step's precision (1 - T may round to 1).
float step_opacity(float T, float dt) {
  return dt == u_box_half.w ? 1.0 - T : 1.0 - pow(max(T, 0.0), dt / u_box_half.w);
}

// The correction from a reference length other than the table's step (preintegrated segments
// of the table's step, used for a segment of length dt).
float correct_opacity_for(float a, float dt, float reference) {
  return 1.0 - pow(max(1.0 - a, 0.0), dt / reference);
}
