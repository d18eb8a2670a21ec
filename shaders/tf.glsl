// GL's transfer-function lookup: the 8192-entry table over the volume's value range as a 1D
// texture, sampled at texel centres (colour, and the transparency of the scene's uniform step,
// baked by the host; ray/compositing.glsl step_opacity corrects it for the step taken).
layout(binding = UNIT_TF) uniform sampler1D u_tf;

bool tf_lookup(float s, out vec4 c) {
  float size = float(TF_TABLE_SIZE);
  c = texture(u_tf, clamp(s, 0.0, 1.0) * ((size - 1.0) / size) + 0.5 / size);
  return true;
}
