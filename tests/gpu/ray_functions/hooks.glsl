// What the shared ray code asks of its target, for the function table (ray_functions_test.cpp):
// a field and TF points that GLSL and C++ compute alike (products and sums only, no texture, no
// transcendental function), so a difference in a row is the shared code's.

// A bowl with a slope, in TF coordinates: rays through it cross values twice, and graze their
// minimum (peak roots near tangencies).
float sample_field(vec3 x) {
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
