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

export function preset(name, lo, hi, iso) {
  const at = (r) => lo + r * (hi - lo);
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
