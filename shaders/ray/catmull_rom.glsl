// The Catmull-Rom spline through p0..p3 at s in [0, 1] between p1 and p2 (Lee et al. 2010 §3.1,
// virtual samples: values and gradients alike).
float catmull_rom(float p0, float p1, float p2, float p3, float s) {
  return 0.5f * (2.0f * p1 + (p2 - p0) * s + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * s * s +
                 (3.0f * p1 - p0 - 3.0f * p2 + p3) * s * s * s);
}
vec3 catmull_rom3(vec3 p0, vec3 p1, vec3 p2, vec3 p3, float s) {
  return 0.5f * (2.0f * p1 + (p2 - p0) * s + (2.0f * p0 - 5.0f * p1 + 4.0f * p2 - p3) * s * s +
                 (3.0f * p1 - p0 - 3.0f * p2 + p3) * s * s * s);
}
