// What a viewer shows around the picture, drawn by the page over the frame: an axes triad (the
// world's x, y, z as the camera sees them), the volume's bounding box, a scale bar in the volume's
// unit (units.js) at the focal plane, and a colour bar of the TF over the data's range. Each can be hidden. The
// projection is the server's (docs/scenes.md: perspective with fov_y, or orthographic with height;
// up orthogonalised), so the box lies on the volume's edges.
import { cross, dot, length, normalize, sub } from './vec.js';
import { planeSection } from './clip-controls.js';
import { niceLength } from './units.js';

const AXES = [[[1, 0, 0], '#e55', 'x'], [[0, 1, 0], '#5d5', 'y'], [[0, 0, 1], '#59f', 'z']];

export class Annotations {
  show = { triad: true, box: true, scale: true, colorbar: true };
  camera = null;
  volume = null;
  tf = null;
  unit = 'units';  // lengths' unit (units.js)
  marks = [];  // the measure's points (world), drawn whatever is hidden
  clip = null;  // render.clip: its box and the plane's cut through the volume, drawn whatever is hidden
  #raf = 0;

  constructor(canvas, disposer) {
    this.canvas = canvas;
    disposer.listen(window, 'resize', () => this.update());
    disposer.add(() => cancelAnimationFrame(this.#raf));
  }

  update(changes = {}) {
    Object.assign(this, changes);
    if (!this.#raf) this.#raf = requestAnimationFrame(() => { this.#raf = 0; this.draw(); });
  }

  // Image position (CSS pixels, row 0 at the top) of world point p, or null behind the eye.
  project(p, w, h) {
    const c = this.camera;
    const forward = normalize(sub(c.center, c.eye)), right = normalize(cross(forward, c.up)), up = cross(right, forward);
    const d = sub(p, c.eye), z = dot(d, forward);
    let x, y;
    if (c.projection === 'orthographic') {
      const half = c.height / 2;
      x = dot(d, right) / (half * (w / h));
      y = dot(d, up) / half;
    } else {
      if (z <= 1e-9) return null;
      const t = Math.tan(((c.fov_y ?? 30) * Math.PI) / 360);
      x = dot(d, right) / (z * t * (w / h));
      y = dot(d, up) / (z * t);
    }
    return [((x + 1) / 2) * w, ((1 - y) / 2) * h];
  }

  draw() {
    const cv = this.canvas, dpr = window.devicePixelRatio || 1;
    const w = cv.clientWidth, h = cv.clientHeight;
    if (cv.width !== Math.round(w * dpr) || cv.height !== Math.round(h * dpr)) {
      cv.width = Math.round(w * dpr);
      cv.height = Math.round(h * dpr);
    }
    const g = cv.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    this.paint(g, w, h);
  }

  // The annotations shown, onto context g of a w x h (CSS pixel) picture: the view's overlay, or a
  // screenshot's (scaled by its context's transform). `still`: no measure marks nor clip handles.
  paint(g, w, h, { still = false } = {}) {
    if (!this.camera || !this.volume || !w || !h) return;
    g.font = '11px system-ui, sans-serif';
    if (this.show.box) this.#box(g, w, h);
    if (this.show.triad) this.#triad(g, w, h);
    if (this.show.scale) this.#scaleBar(g, w, h);
    if (this.show.colorbar && this.tf) this.#colorBar(g, w, h);
    if (still) return;
    if (this.marks.length) this.#marks(g, w, h);
    if (this.clip) this.#clip(g, w, h);
  }

  #clip(g, w, h) {
    const line = (pts, closed) => {
      g.beginPath();
      pts.forEach((p, i) => (i ? g.lineTo(...p) : g.moveTo(...p)));
      if (closed) g.closePath();
      g.stroke();
    };
    g.lineWidth = 1.5;
    if (this.clip.box) {
      const [lo, hi] = this.clip.box, k = [];
      for (let i = 0; i < 8; i++) k.push(this.project([i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]], w, h));
      g.strokeStyle = g.fillStyle = '#f93';
      for (let i = 0; i < 8; i++)
        for (const bit of [1, 2, 4]) if ((i | bit) !== i && k[i] && k[i | bit]) line([k[i], k[i | bit]]);
      // A handle on each face's centre: drag it to move the face (clip-controls.js).
      const c = lo.map((l, a) => (l + hi[a]) / 2);
      for (let a = 0; a < 3; a++)
        for (const v of [lo[a], hi[a]]) {
          const p = [...c];
          p[a] = v;
          const s = this.project(p, w, h);
          if (s) g.fillRect(s[0] - 4, s[1] - 4, 8, 8);
        }
    }
    if (this.clip.plane) {
      const [lo, hi] = [this.corners()[0], this.corners()[7]];
      const poly = planeSection(lo, hi, this.clip.plane.point, this.clip.plane.normal).map((p) => this.project(p, w, h));
      g.strokeStyle = '#4df';
      if (poly.length && poly.every(Boolean)) line(poly, true);
    }
  }

  #marks(g, w, h) {
    const pts = this.marks.map((p) => this.project(p, w, h));
    g.strokeStyle = '#fd4';
    g.lineWidth = 2;
    g.beginPath();
    if (pts.length === 2 && pts[0] && pts[1]) {
      g.moveTo(...pts[0]);
      g.lineTo(...pts[1]);
    }
    for (const p of pts) if (p) { g.moveTo(p[0] + 5, p[1]); g.arc(p[0], p[1], 5, 0, 2 * Math.PI); }
    g.stroke();
  }

  corners() {
    const v = this.volume, lo = v.origin, hi = v.origin.map((o, a) => o + (v.dims[a] - 1) * v.spacing[a]);
    const out = [];
    for (let i = 0; i < 8; i++) out.push([i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]]);
    return out;
  }

  #box(g, w, h) {
    const pts = this.corners().map((p) => this.project(p, w, h));
    g.strokeStyle = '#aab8';
    g.lineWidth = 1;
    g.beginPath();
    for (let i = 0; i < 8; i++)
      for (const bit of [1, 2, 4]) {
        const j = i | bit;
        if (j === i || !pts[i] || !pts[j]) continue;
        g.moveTo(...pts[i]);
        g.lineTo(...pts[j]);
      }
    g.stroke();
  }

  #triad(g, w, h) {
    const c = this.camera;
    const forward = normalize(sub(c.center, c.eye)), right = normalize(cross(forward, c.up)), up = cross(right, forward);
    const o = [w - 52, h - 52], r = 34;
    // Farthest axis first, so the nearer ones are drawn over it.
    const axes = AXES.map(([a, color, name]) => ({ a, color, name, depth: dot(a, forward) })).sort((p, q) => q.depth - p.depth);
    g.lineWidth = 2;
    for (const { a, color, name } of axes) {
      const x = o[0] + dot(a, right) * r, y = o[1] - dot(a, up) * r;
      g.strokeStyle = color;
      g.beginPath();
      g.moveTo(...o);
      g.lineTo(x, y);
      g.stroke();
      g.fillStyle = color;
      g.fillText(name, x + (x >= o[0] ? 3 : -9), y + (y >= o[1] ? 10 : -3));
    }
  }

  // Lengths (the volume's unit) per CSS pixel at the focal plane (the camera's centre).
  unitsPerPixel(h) {
    const c = this.camera;
    if (c.projection === 'orthographic') return c.height / h;
    return (2 * length(sub(c.center, c.eye)) * Math.tan(((c.fov_y ?? 30) * Math.PI) / 360)) / h;
  }

  #scaleBar(g, w, h) {
    const per = this.unitsPerPixel(h);
    const { length: nice, label } = niceLength(120 * per, this.unit);
    const px = nice / per, x = 16, y = h - 44;
    g.strokeStyle = g.fillStyle = '#dde';
    g.lineWidth = 2;
    g.beginPath();
    g.moveTo(x, y - 5);
    g.lineTo(x, y);
    g.lineTo(x + px, y);
    g.lineTo(x + px, y - 5);
    g.stroke();
    g.fillText(`${label} (at the centre)`, x, y - 8);
  }

  #colorBar(g, w, h) {
    const [lo, hi] = this.volume.range, pts = this.tf, x = w - 30, top = 40, bottom = Math.max(top + 60, h - 120);
    for (let y = top; y <= bottom; y++) {
      const v = hi - ((y - top) / (bottom - top)) * (hi - lo);
      const c = colourAt(pts, v);
      g.fillStyle = `rgb(${c.map((k) => Math.round(255 * k)).join(',')})`;
      g.fillRect(x, y, 12, 1);
    }
    g.strokeStyle = '#888';
    g.strokeRect(x - 0.5, top - 0.5, 13, bottom - top + 1);
    g.fillStyle = '#dde';
    g.textAlign = 'right';
    g.fillText(String(+hi.toPrecision(4)), x - 4, top + 8);
    g.fillText(String(+lo.toPrecision(4)), x - 4, bottom);
    g.textAlign = 'left';
  }
}

// The TF's colour at v (linear between points, constant outside).
function colourAt(points, v) {
  const i = points.findIndex((p) => p[0] > v);
  if (i === -1) return points[points.length - 1].slice(1, 4);
  if (i === 0) return points[0].slice(1, 4);
  const a = points[i - 1], b = points[i], t = (v - a[0]) / (b[0] - a[0] || 1);
  return [1, 2, 3].map((k) => a[k] + (b[k] - a[k]) * t);
}
