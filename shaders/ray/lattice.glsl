// Where a ray's samples lie (server/core/sampling.h is the reference's definition):
//   t_j = t0 + j * (B + A * j / 2), j = 0, 1, ...   from the box entry t0, computed from j.
// Uniform: A = 0, B = the step. Differential (Knoll §5, eq. 10-18): the step grows by A = k |dD/dx|
// per sample from B = max(k + A * x_enter, min step), x_enter the eye-based index of the entry.
// Adaptive (Knoll §6.2): a macrocell with multiplier M visits the multiples of M only.

float lattice_t(IN(Lattice) L, float j) { return L.t0 + j * (L.B + L.A * j * 0.5f); }
// t(j + m) - t(j) without cancellation: the step a sample visited with stride m stands for.
float lattice_step(IN(Lattice) L, float j, float m) { return m * (L.B + L.A * (j + 0.5f * m)); }
// Continuous index x with t(x) = t (t >= t0); stable as A -> 0. On a uniform lattice (A = 0:
// no differential sampling) 2d / (B + sqrt(B^2)) is d / B exactly (the square root of a rounded
// square is |B|, halving is exact), without the square root; a test of the variant, not of A, so
// that GLSL folds it.
float lattice_index(IN(Lattice) L, float t) {
  float d = max(0.0f, t - L.t0);
  if (!V.differential) return d / L.B;
  return 2.0f * d / (L.B + sqrt(L.B * L.B + 2.0f * L.A * d));
}

Lattice ray_lattice(IN(Ray) r, float t_enter) {
  Lattice L;
  L.t0 = t_enter;
  if (V.differential) {
    vec3 d = r.d / dot(r.d, P.forward);                                    // depth-1 direction (eq. 7)
    vec3 u = P.right * (2.0f * P.half_width / float(P.image_width));      // one pixel along x
    float dd = dot(d, d);
    float dD_dx = length(dd * u - dot(d, u) * d) / (dd * sqrt(dd));       // eq. 10
    float k = P.differential_k;
    float a = k * dD_dx;
    float s = max(0.0f, t_enter - r.t_eye);                                // eye -> box entry
    float x = 2.0f * s / (k + sqrt(k * k + 2.0f * a * s));                 // eq. 18, stable form
    L.A = a;
    L.B = max(k + a * x, P.min_step);
  } else {
    L.A = 0.0f;
    L.B = P.step;
  }
  return L;
}

// The chord a sample stands for (midpoint rule): lattice index i visited with stride m stands
// for the lattice's [i - 1/2, i + m - 1/2], cut at the ray's entry and exit: its whole step
// (`step`, lattice_step(L, i, m)) but at the ray's ends, where chord_head and chord_tail (the
// whole ray's, with `ray_last` its last lattice index) correct it.
float chord_head(IN(Lattice) L) { return -lattice_step(L, 0.0f, 0.5f); }
float chord_tail(IN(Lattice) L, float t_exit, int ray_last) {
  float j = float(ray_last);
  return min(t_exit - lattice_t(L, j), lattice_step(L, j, 1.0f)) - lattice_step(L, j, 0.5f);
}
RAY_COLD float chord_at_ends(float step, int i, int m, float head, float tail, int ray_last) {
  if (i == 0) step += head;
  if (i + m > ray_last) step += tail;
  return step;
}
