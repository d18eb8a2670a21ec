// What the shared ray code asks of its target, for the function table (ray_functions_test.cpp):
// a field and TF points that GLSL and C++ compute alike (products and sums only, no texture, no
// transcendental function), so a difference in a row is the shared code's.

// A bowl with a slope, in TF coordinates: rays through it cross values twice, and graze their
// minimum (peak roots near tangencies).
float sample_field(IN(Ray) r, vec3 x) {
  vec3 d = x - vec3(7.5f, 8.25f, 9.0f);
  return 0.002f * dot(d, d) + 0.01f * x.x;
}

// Four TF points at 0, 1/3, 2/3, 1 (tf_point(2k): the value in .x; tf_point(2k + 1): colour, opacity).
vec4 tf_point(int k) {
  int p = k / 2;
  float v = float(p) / 3.0f;
  if (k - 2 * p == 0) return vec4(v, 0.0f, 0.0f, 0.0f);
  return vec4(0.2f + 0.25f * v, 0.9f - 0.5f * v, 0.4f, 0.05f + 0.3f * v);
}

// Central differences of the field one voxel apart, per world unit (as the targets' own).
vec3 field_gradient(IN(Ray) r, vec3 x) {
  vec3 g;
  g.x = sample_field(r, x + vec3(1.0f, 0.0f, 0.0f)) - sample_field(r, x - vec3(1.0f, 0.0f, 0.0f));
  g.y = sample_field(r, x + vec3(0.0f, 1.0f, 0.0f)) - sample_field(r, x - vec3(0.0f, 1.0f, 0.0f));
  g.z = sample_field(r, x + vec3(0.0f, 0.0f, 1.0f)) - sample_field(r, x - vec3(0.0f, 0.0f, 1.0f));
  return g / (2.0f * r.spacing);
}

// A peak table whose cell (i, j) lists the peaks at 1/3 and 2/3 where the bins' values could
// bracket them, ascending; empty slots after them.
vec4 peak_slots(int i, int j, int layer) {
  float lo = float(min(i, j)) / float(P.peak_bins), hi = float(max(i, j) + 1) / float(P.peak_bins);
  vec4 slots = vec4(NO_PEAK_TEXEL);
  int n = 0;
  for (int p = 1; p <= 2; ++p) {
    float v = float(p) / 3.0f;
    if (layer == 0 && lo <= v && v <= hi) {
      slots[n] = v;
      n += 1;
    }
  }
  return slots;
}
bool peak_cell_any(int i, int j) { return true; }

// A TF with opacity edges (transparent, a band at 0.3..0.5, opaque from 0.8), its fourth channel
// the transparency of the uniform step; a preintegration table from the same values.
bool tf_lookup(float s, OUT(vec4) c) {
  float T = s < 0.3f ? 1.0f : (s < 0.5f ? 0.6f : (s < 0.8f ? 0.95f : 0.0f));
  c = vec4(s, 1.0f - s, 0.5f, T);
  return T < 1.0f;
}
bool preint_lookup(IN(Ray) r, float s_front, float s_back, OUT(vec4) c) {
  float a = clamp(0.5f * (s_front + s_back), 0.0f, 1.0f);
  c = vec4(0.3f * a, 0.2f * a, 0.1f * a, a);
  return a > 0.0f;
}
