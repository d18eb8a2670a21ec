// Peak finding between samples (Knoll et al. 2009 §4.2, Alg. 1, errata in docs/architecture.md).
// C++ twins: core/peaks.cpp (table lookup) and reference/cpu_raycaster.cpp (root solving).
layout(binding = UNIT_PEAK_TABLE) uniform sampler2DArray u_peak_table;  // RGBA32F: 4 peak values per layer, NO_PEAK_TEXEL = none
layout(std430, binding = SSBO_TF_POINTS) readonly buffer TfPoints {
  vec4 tf_points[];  // per TF point: (value in TF coordinates, 0, 0, 0), then (r, g, b, a)
};

// The TF evaluated exactly from its points: a Dirac-like peak is narrower than a table entry.
vec4 tf_exact(float v) {
  int n = int(u_tables.y);
  int lo = 0, hi = n;  // first point with value > v
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (tf_points[2 * mid].x > v) hi = mid; else lo = mid + 1;
  }
  if (lo == 0) return tf_points[1];
  if (lo == n) return tf_points[2 * n - 1];
  float va = tf_points[2 * (lo - 1)].x, vb = tf_points[2 * lo].x;
  return mix(tf_points[2 * (lo - 1) + 1], tf_points[2 * lo + 1], (v - va) / (vb - va));
}

int peak_bin(float f) { return clamp(int(floor(f * u_peaks.x)), 0, int(u_peaks.x) - 1); }

// The errata: the segment f0 -> f1 crosses v when min < v <= max (both equal: no crossing).
bool crosses(float f0, float f1, float v) { return min(f0, f1) < v && v <= max(f0, f1); }

// Regula falsi (secant steps kept inside the bracket), guarded against g_a == g_b.
float solve_root(Ray r, float t0, float f0, float t1, float f1, float v, inout float evaluations) {
  float ta = t0, tb = t1, ga = f0 - v, gb = f1 - v;
  for (int k = 0; k < int(u_peaks.w); ++k) {
    if (gb == ga) break;
    float t = clamp(ta - ga * (tb - ta) / (gb - ga), min(ta, tb), max(ta, tb));
    float g = sample_field(voxel_coords(r.o + t * r.d)) - v;
    evaluations += 1.0;
    if ((g >= 0.0) == (ga >= 0.0)) {
      ta = t;
      ga = g;
    } else {
      tb = t;
      gb = g;
    }
  }
  return gb == ga ? 0.5 * (ta + tb) : clamp(ta - ga * (tb - ta) / (gb - ga), min(ta, tb), max(ta, tb));
}

// Finds and composites, in ray order, up to max-peaks peaks crossed by the segment; returns
// true when it found one.
bool find_peaks(Ray r, float t0, float f0, float t1, float f1, inout RayResult res) {
  int i = peak_bin(f0), j = peak_bin(f1);
  bool reverse = (i == j) && f0 > f1;  // the diagonal is stored ascending
  int max_peaks = int(u_peaks.z);
  float found[4];
  int n = 0;
  bool done = false;
  for (int layer = 0; layer < int(u_peaks.y) && !done; ++layer) {
    vec4 slots = texelFetch(u_peak_table, ivec3(i, j, layer), 0);
    for (int s = 0; s < 4; ++s) {
      float v = slots[s];
      if (v == NO_PEAK_TEXEL) {
        done = true;
        break;
      }
      if (!crosses(f0, f1, v)) continue;
      if (reverse) {  // keep the last four in table order: the first four along the ray
        if (n == 4) {
          found[0] = found[1];
          found[1] = found[2];
          found[2] = found[3];
          n = 3;
        }
        found[n++] = v;
      } else {
        found[n++] = v;
        if (n == max_peaks) {
          done = true;
          break;
        }
      }
    }
  }
  int count = min(n, max_peaks);
  if (!DRAWN) return count > 0;  // another brick's consume (raycast_body.glsl g_draw): whether it holds a peak only
  for (int k = 0; k < count; ++k) {
    float v = reverse ? found[n - 1 - k] : found[k];
    vec4 c = tf_exact(v);
    vec3 rgb = c.rgb;
#ifdef SHADING
    float t = solve_root(r, t0, f0, t1, f1, v, res.samples);
    rgb = shade(rgb, field_gradient(voxel_coords(r.o + t * r.d)), r.d);
#else
    // Only shading uses the root's position: count what solve_root would evaluate. The bracket's
    // ends keep opposite signs, so it takes every step unless they start equal.
    precise float ga = f0 - v, gb = f1 - v;  // as solve_root's start, not rewritten as f0 == f1
    res.samples += (ga == gb) ? 0.0 : u_peaks.w;
#endif
    composite(res.acc, rgb, c.a * PEAK_WEIGHT);  // unscaled opacity at the peak (Knoll §4.2)
    if (res.acc.a >= STOP) break;
  }
  return count > 0;
}
