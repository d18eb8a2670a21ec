// Transfer-function lookup (8192-entry table over the volume's value range, sampled at texel
// centres) and the opacity correction for the step actually taken (DESIGN §4a).
layout(binding = UNIT_TF) uniform sampler1D u_tf;

vec4 tf_lookup(float s) {
  float size = u_value_map.z;
  return texture(u_tf, (0.5 + clamp(s, 0.0, 1.0) * (size - 1.0)) / size);
}

float correct_opacity(float a, float dt) {
  return 1.0 - pow(max(1.0 - a, 0.0), dt / u_spacing.w);
}

// The same correction from a reference length other than the opacity unit (preintegrated
// segments of the table's step, used for a segment of length dt).
float correct_opacity_for(float a, float dt, float reference) {
  return 1.0 - pow(max(1.0 - a, 0.0), dt / reference);
}
