// Peak finding's arithmetic (Knoll et al. 2009 §4.2, Algorithm 1, errata in
// docs/architecture.md): the bin of a value in the peak table, the crossing test, the root of
// f(t) = v between two samples, and the TF evaluated exactly at a peak. Reads the target's field
// (sample_field) and TF points (tf_point).

SHARED_CONST float kNoPeakTexel = NO_PEAK_TEXEL;  // an empty slot of the peak table (the host's value)

// The peak table's bin of a value in TF coordinates.
int peak_bin(float f, int bins) { return clamp(int(floor(f * float(bins))), 0, bins - 1); }

// The errata: the segment f0 -> f1 crosses v when min < v <= max (both equal: no crossing).
bool crosses(float f0, float f1, float v) { return min(f0, f1) < v && v <= max(f0, f1); }

// Regula falsi (secant steps kept inside the bracket), guarded against ga == gb; each field
// evaluation is counted in `evaluations`.
float solve_root(IN(Ray) r, float t0, float f0, float t1, float f1, float v, INOUT(float) evaluations) {
  float ta = t0, tb = t1, ga = f0 - v, gb = f1 - v;
  for (int k = 0; k < P.secant_iterations; ++k) {
    if (gb == ga) break;
    float t = clamp(ta - ga * (tb - ta) / (gb - ga), min(ta, tb), max(ta, tb));
    float g = sample_field(r, voxel_at(r, t)) - v;
    evaluations += 1.0f;
    if ((g >= 0.0f) == (ga >= 0.0f)) {
      ta = t;
      ga = g;
    } else {
      tb = t;
      gb = g;
    }
  }
  return gb == ga ? 0.5f * (ta + tb) : clamp(ta - ga * (tb - ta) / (gb - ga), min(ta, tb), max(ta, tb));
}

// What solve_root counts, without sampling (only shading uses the root's position): the
// bracket's ends keep opposite signs (each step replaces the end of its own sign), so ga never
// equals gb after the start and regula falsi takes every step unless they start equal.
float root_evaluations(float f0, float f1, float v) {
  PRECISE float ga = f0 - v;
  PRECISE float gb = f1 - v;  // as solve_root's start, not rewritten as f0 == f1
  return ga == gb ? 0.0f : float(P.secant_iterations);
}

// The TF evaluated exactly from its points (tf_point(2k): the value in TF coordinates in .x,
// tf_point(2k + 1): its colour and opacity): a Dirac-like peak is narrower than a table entry.
vec4 tf_exact(float v) {
  int n = P.tf_point_count;
  int lo = 0, hi = n;  // first point with value > v
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (tf_point(2 * mid).x > v)
      hi = mid;
    else
      lo = mid + 1;
  }
  if (lo == 0) return tf_point(1);
  if (lo == n) return tf_point(2 * n - 1);
  float va = tf_point(2 * (lo - 1)).x, vb = tf_point(2 * lo).x;
  return mix(tf_point(2 * (lo - 1) + 1), tf_point(2 * lo + 1), (v - va) / (vb - va));
}

// The cell (i, j) of the table holds a peak: its slots walked, the peaks composited (out of line
// on the CPU: most segments find their cell empty and stop in find_peaks).
RAY_COLD bool peaks_in_cell(IN(Ray) r, INOUT(RayState) s, int i, int j, float t0, float f0, float t1, float f1) {
  bool reverse = (i == j) && f0 > f1;  // the diagonal is stored ascending
  int max_peaks = P.max_peaks;
  float found[4];
  int n = 0;
  bool done = false;
  for (int layer = 0; layer < P.peak_layers && !done; ++layer) {
    vec4 slots = peak_slots(i, j, layer);
    for (int q = 0; q < 4; ++q) {
      float v = slots[q];
      if (v == kNoPeakTexel) {
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
  if (V.brick && !s.draw) return count > 0;  // another brick's consume: whether it holds a peak only
  for (int k = 0; k < count; ++k) {
    float v = reverse ? found[n - 1 - k] : found[k];
    vec4 c = tf_exact(v);
    vec3 rgb = vec3(c);
    if (V.shading) {
      float t = solve_root(r, t0, f0, t1, f1, v, s.samples);
      rgb = shade(r, rgb, field_gradient(r, voxel_at(r, t)));
    } else {
      s.samples += root_evaluations(f0, f1, v);  // only shading uses the root's position
    }
    composite(s.acc, rgb, c.w * (V.ray_texture ? s.peak_weight : 1.0f));  // unscaled opacity at the peak (Knoll §4.2)
    if (s.acc.w >= s.stop) break;
  }
  return count > 0;
}

// Finds and composites, in ray order, up to P.max_peaks peaks crossed by the segment
// (t0, f0) -> (t1, f1); true when it found one. Reads the peak table through the target's
// peak_cell_any (false: the table's cell holds no peak, without reading it) and peak_slots (the
// four values of a layer, NO_PEAK_TEXEL after the last).
bool find_peaks(IN(Ray) r, INOUT(RayState) s, float t0, float f0, float t1, float f1) {
  int i = peak_bin(f0, r.peak_bins), j = peak_bin(f1, r.peak_bins);
  return peak_cell_any(i, j) && peaks_in_cell(r, s, i, j, t0, f0, t1, f1);
}
