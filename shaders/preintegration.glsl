// Pre-integrated classification: the segment's colour (opacity-weighted) and opacity from the
// 2D table built by core/preintegration.cpp for the current step.
layout(binding = UNIT_PREINT) uniform sampler2D u_preint;

bool preint_lookup(Ray r, float s_front, float s_back, out vec4 c) {
  float n = float(r.preint_size);
  vec2 uv = clamp(vec2(s_front, s_back), 0.0, 1.0) * ((n - 1.0) / n) + 0.5 / n;
  c = texture(u_preint, uv);
  return true;
}
