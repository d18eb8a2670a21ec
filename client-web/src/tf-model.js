// The transfer function as data: points [value, r, g, b, a] in the volume's units, presets,
// peak detection (the server's rule, core/peaks.cpp) and undo/redo of full states.
export function findPeaks(points) {
  const peaks = [];
  for (let k = 0; k < points.length;) {
    let e = k;
    while (e + 1 < points.length && points[e + 1][4] === points[k][4]) e++;
    const leftLower = k > 0 && points[k - 1][4] < points[k][4];
    const rightLower = e + 1 < points.length && points[e + 1][4] < points[e][4];
    if (leftLower && rightLower && points[k][4] > 0) peaks.push((points[k][0] + points[e][0]) / 2);
    k = e + 1;
  }
  return peaks;
}

export function interpolate(points, v) {
  let i = points.findIndex((p) => p[0] > v);
  if (i === -1) return points[points.length - 1].slice(1);
  if (i === 0) return points[0].slice(1);
  const a = points[i - 1], b = points[i], w = (v - a[0]) / (b[0] - a[0]);
  return a.slice(1).map((x, c) => x + (b[c + 1] - x) * w);
}

// What a preset needs of the render settings to show what it is for.
export const PRESET_NEEDS = {
  iso: { classification: 'peaks', shading: true },
  'ct-bone': { classification: 'preint', shading: true },
  'ct-soft': { classification: 'preint', shading: true },
  em: { classification: 'post', shading: false },
};

// Hounsfield values where the volume says it holds them (its info's value_unit: a CT series, a
// sidecar's "values": "HU"), clamped into its range; on other data the preset's points spread
// over the data's range in their order.
function hu(lo, hi, values, inHu) {
  return values.map((v, k) => (inHu ? Math.min(Math.max(v, lo), hi) : lo + ((k + 1) / (values.length + 1)) * (hi - lo)));
}

// The named colour maps (sRGB stops in [0, 1], evenly spaced): the server's, from
// GET /api/colormaps (loadColormaps), so the viewer's presets and the automatic TF (viridis)
// are one source; empty until they arrive.
export const COLORMAPS = {};

// Fills COLORMAPS from the server once; false when it could not be asked (no token yet, offline).
export async function loadColormaps(fetchJson) {
  if (Object.keys(COLORMAPS).length) return true;
  try {
    const { colormaps } = await fetchJson('/api/colormaps');
    Object.assign(COLORMAPS, colormaps);
    return true;
  } catch {
    return false;
  }
}

// Otsu's threshold of a histogram of equal bins over [lo, hi], as the server's automatic TF
// finds it (core/auto_tf.cpp): the bin boundary with the largest between-class variance; lo
// when there is nothing to split.
export function otsuThreshold(histogram, lo, hi) {
  const n = histogram?.length ?? 0;
  let total = 0, sum = 0;
  for (let b = 0; b < n; b++) { total += histogram[b]; sum += b * histogram[b]; }
  if (!n || total <= 0 || !(hi > lo)) return lo;
  let w0 = 0, sum0 = 0, best = -1, split = 0;
  for (let k = 1; k < n; k++) {
    w0 += histogram[k - 1];
    sum0 += (k - 1) * histogram[k - 1];
    const w1 = total - w0;
    if (w0 <= 0 || w1 <= 0) continue;
    const d = sum0 / w0 - (sum - sum0) / w1, between = w0 * w1 * d * d;
    if (between > best) { best = between; split = k; }
  }
  return lo + ((hi - lo) * split) / n;
}

// A colour map over [lo, hi] with opacity rising from 0 at `start` (the background's end: below
// it the map's colours stay clear) to `top` at hi (an opacity ramp, DVR).
export function colormapTf(name, lo, hi, top = 0.6, start = lo) {
  const stops = COLORMAPS[name];
  const from = start < hi ? Math.max(start, lo) : lo;
  return stops.map((c, k) => {
    const v = lo + (k / (stops.length - 1)) * (hi - lo);
    return [v, c[0], c[1], c[2], top * Math.max(0, (v - from) / (hi - from))];
  });
}

// Rescales the TF's points from their span to the window [level - window/2, level + window/2]
// (window/level as in radiology viewers: the same TF over another range of values).
export function windowLevel(points, window, level) {
  const a = points[0][0], b = points[points.length - 1][0];
  const lo = level - window / 2, span = b - a || 1;
  return points.map((p) => [lo + ((p[0] - a) / span) * window, ...p.slice(1)]);
}

// `histogram` (equal bins over [lo, hi]) places a colour map's opacity ramp above the data's
// background (Otsu's threshold), as the automatic TF's: a CT's air and its noise stay clear.
export function preset(name, lo, hi, iso, inHu = false, histogram = null) {
  const at = (r) => lo + r * (hi - lo);
  if (COLORMAPS[name]) return colormapTf(name, lo, hi, 0.6, otsuThreshold(histogram, lo, hi));
  switch (name) {
    case 'ct-bone': {  // CT in Hounsfield units: bone above ~300 HU, soft tissue faint
      const [s0, s1, b0] = hu(lo, hi, [-100, 200, 300], inHu);
      return [[lo, 0, 0, 0, 0], [s0, 0.7, 0.4, 0.3, 0], [s1, 0.85, 0.55, 0.45, 0.05], [b0, 1, 0.95, 0.85, 0.6], [hi, 1, 1, 0.95, 0.9]];
    }
    case 'ct-soft': {  // CT soft tissue: fat to muscle (-100..100 HU), bone dim
      const [f0, m0, m1] = hu(lo, hi, [-150, 20, 150], inHu);
      return [[lo, 0, 0, 0, 0], [f0, 0.9, 0.7, 0.55, 0], [m0, 0.85, 0.35, 0.3, 0.15], [m1, 0.95, 0.75, 0.65, 0.25], [hi, 1, 1, 1, 0.3]];
    }
    case 'em':  // electron microscopy: membranes and organelles are dark; they become opaque
      return [[lo, 0.95, 0.9, 0.8, 0.6], [at(0.35), 0.7, 0.6, 0.5, 0.15], [at(0.55), 0.5, 0.5, 0.5, 0], [hi, 0.5, 0.5, 0.5, 0]];
  }
  switch (name) {
    case 'grey': return [[lo, 0, 0, 0, 0], [hi, 1, 1, 1, 1]];
    case 'coolwarm':
      return [[lo, 0.23, 0.3, 0.75, 0], [at(0.5), 0.87, 0.87, 0.87, 0.15], [hi, 0.71, 0.02, 0.15, 0.8]];
    case 'hot':
      return [[lo, 0, 0, 0, 0], [at(0.35), 0.9, 0, 0, 0.05], [at(0.7), 1, 0.8, 0, 0.3], [hi, 1, 1, 1, 0.8]];
    case 'iso': {  // a narrow peak: an isosurface for peak finding (Knoll §4)
      const v = Math.min(Math.max(iso ?? at(0.5), at(0.001)), at(0.999)), w = 1e-3 * (hi - lo);
      return [[lo, 0.9, 0.9, 0.9, 0], [v - w, 0.9, 0.9, 0.9, 0], [v, 0.95, 0.85, 0.7, 0.9], [v + w, 0.9, 0.9, 0.9, 0], [hi, 0.9, 0.9, 0.9, 0]];
    }
  }
  return null;
}

export class TfHistory {
  #undo = [];
  #redo = [];
  push(state) { this.#undo.push(structuredClone(state)); this.#redo.length = 0; if (this.#undo.length > 200) this.#undo.shift(); }
  undo(current) { if (!this.#undo.length) return null; this.#redo.push(structuredClone(current)); return this.#undo.pop(); }
  redo(current) { if (!this.#redo.length) return null; this.#undo.push(structuredClone(current)); return this.#redo.pop(); }
}
