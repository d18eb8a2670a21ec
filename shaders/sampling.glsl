// Where a ray's samples lie (server/core/sampling.h is the definition and the CPU twin):
//   t_j = t0 + j * (B + A * j / 2), j = 0, 1, ...   from the box entry t0, computed from j.
// Uniform: A = 0, B = the step. DIFFERENTIAL (Knoll §5, eq. 10-18): the step grows by A = k |dD/dx|
// per sample from B = max(k + A * x_enter, min step), x_enter the eye-based index of the entry.
// ADAPTIVE (Knoll §6.2): a macrocell with multiplier M visits the multiples of M only.

// Byte c of a per-macrocell table (grid order, four bytes to a uint, low byte first).
#define cell_byte(table, c) \
  ((table[cell_index(c) >> 2] >> (8 * (cell_index(c) & 3))) & 0xFFu)
int cell_index(ivec3 c) { return c.x + int(u_cells.x) * (c.y + int(u_cells.y) * c.z); }

struct Lattice {
  float t0, A, B;
};

float lattice_t(Lattice L, float j) { return L.t0 + j * (L.B + L.A * j * 0.5); }
// t(j + m) - t(j) without cancellation: the step a sample visited with stride m stands for.
float lattice_step(Lattice L, float j, float m) { return m * (L.B + L.A * (j + 0.5 * m)); }
// Continuous index x with t(x) = t (t >= t0); stable as A -> 0.
float lattice_index(Lattice L, float t) {
  float d = max(0.0, t - L.t0);
  return 2.0 * d / (L.B + sqrt(L.B * L.B + 2.0 * L.A * d));
}

Lattice ray_lattice(Ray r, float t_enter) {
  Lattice L;
  L.t0 = t_enter;
#ifdef DIFFERENTIAL
  vec3 d = r.d / dot(r.d, u_forward.xyz);                          // depth-1 direction (eq. 7)
  vec3 u = u_right.xyz * (2.0 * u_right.w / float(u_image.x));     // one pixel along x
  float dd = dot(d, d);
  float dD_dx = length(dd * u - dot(d, u) * d) / (dd * sqrt(dd));  // eq. 10
  float k = u_tables.z;
  float a = k * dD_dx;
  float s = max(0.0, t_enter - r.t_eye);                           // eye -> box entry
  float x = 2.0 * s / (k + sqrt(k * k + 2.0 * a * s));             // eq. 18, stable form
  L.A = a;
  L.B = max(k + a * x, u_tables.w);
#else
  L.A = 0.0;
  L.B = u_box_half.w;
#endif
  return L;
}

#ifdef ADAPTIVE
// Per macrocell: multiplier M, 1..8.
layout(std430, binding = SSBO_CELL_STRIDE) readonly buffer CellStride { uint u_cell_stride[]; };
#endif
