// Peak finding between samples (Knoll et al. 2009 §4.2, Alg. 1, errata in docs/architecture.md):
// GL's peak table and TF points, and the walk over a segment's table slots. The bins, the
// crossing test, the roots and the exact TF are ray/peaks.glsl.
layout(binding = UNIT_PEAK_TABLE) uniform sampler2DArray u_peak_table;  // RGBA32F: 4 peak values per layer, NO_PEAK_TEXEL = none
layout(std430, binding = SSBO_TF_POINTS) readonly buffer TfPoints {
  vec4 tf_points[];  // per TF point: (value in TF coordinates, 0, 0, 0), then (r, g, b, a)
};

vec4 tf_point(int k) { return tf_points[k]; }

#include "ray/peaks.glsl"

// Finds and composites, in ray order, up to max-peaks peaks crossed by the segment; returns
// true when it found one.
bool find_peaks(Ray r, float t0, float f0, float t1, float f1, inout RayResult res) {
  int i = peak_bin(f0), j = peak_bin(f1);
  bool reverse = (i == j) && f0 > f1;  // the diagonal is stored ascending
  int max_peaks = P.max_peaks;
  float found[4];
  int n = 0;
  bool done = false;
  for (int layer = 0; layer < P.peak_layers && !done; ++layer) {
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
    res.samples += root_evaluations(f0, f1, v);
#endif
    composite(res.acc, rgb, c.a * PEAK_WEIGHT);  // unscaled opacity at the peak (Knoll §4.2)
    if (res.acc.a >= STOP) break;
  }
  return count > 0;
}
