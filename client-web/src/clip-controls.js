// Clipping (docs/scenes.md, render.clip): a crop box, set by a pair of sliders per axis or by
// dragging the handles on its six faces in the view, and one clip plane, turned to face the viewer
// or an axis and moved along its normal by its slider or by Ctrl+drag in the view (up: further in). Each change goes out as `render.clip` (null: none), one
// per animation frame; the annotations draw the box and the plane's cut through the volume.
import { formatLength } from './units.js';
import { add, dot, normalize, scale, sub } from './vec.js';

const AXES = ['x', 'y', 'z'];
const DRAG_SPEED = 1.5;  // the box diagonal per view height of Ctrl+drag
const HANDLE_PX = 9;     // how near (CSS pixels) a press must be to a face's handle to drag it

export class ClipControls extends EventTarget {
  box = null;    // [[x0, y0, z0], [x1, y1, z1]] or null
  plane = null;  // { normal, offset }: the point is centre + offset * normal; null: none
  #volume = null;
  unit = 'units';  // lengths' unit (units.js), in the readout
  #raf = 0;
  #drag = null;
  #kept = null;  // the box turned off, shown (disabled) and back when turned on again

  constructor(ui, { camera, canvas, project }, disposer) {
    super();
    Object.assign(this, { ui, camera, canvas, project });
    disposer.listen(ui.boxOn, 'change', () => {
      if (!ui.boxOn.checked) this.#kept = this.box;  // off keeps the sliders where they are, to compare
      this.box = ui.boxOn.checked ? (this.#kept ?? this.#bounds()) : null;
      this.#sync();
    });
    for (const input of ui.sliders) disposer.listen(input, 'input', () => this.#fromSliders());
    disposer.listen(ui.planeOn, 'change', () => this.setPlane(ui.planeOn.checked ? this.#facing() : null));
    disposer.listen(ui.facing, 'click', () => this.setPlane(this.#facing()));
    for (const b of ui.axes) disposer.listen(b, 'click', () => this.setPlane({ normal: axis(b.dataset.axis), offset: 0 }));
    disposer.listen(ui.flip, 'click', () => this.plane && this.setPlane({ normal: scale(this.plane.normal, -1), offset: -this.plane.offset }));
    disposer.listen(ui.offset, 'input', () => this.plane && this.setPlane({ ...this.plane, offset: +ui.offset.value }));
    // Ctrl+drag in the view moves the plane along its normal (the camera leaves that drag alone).
    // A press on a face's handle drags that face (the camera leaves both drags alone).
    const ignore = camera.ignore;
    camera.ignore = (e) => (e.button === 0 && ((this.plane && e.ctrlKey) || !!this.handleAt(e))) || ignore(e);
    disposer.add(() => { camera.ignore = ignore; });
    disposer.listen(canvas, 'pointerdown', (e) => {
      if (e.button !== 0) return;
      const face = this.handleAt(e);
      if (face) {
        // The screen movement of one world unit along the face's axis: a drag moves the face by
        // the drag's share of it.
        const q = [...face.p];
        q[face.a] += 1;
        const s1 = this.project(q);
        if (!s1) return;
        this.#drag = { face, x: e.clientX, y: e.clientY, value: this.box[face.side][face.a], unit: [s1[0] - face.s[0], s1[1] - face.s[1]] };
      } else if (this.plane && e.ctrlKey) {
        this.#drag = { y: e.clientY, offset: this.plane.offset };
      } else return;
      canvas.setPointerCapture(e.pointerId);
    });
    disposer.listen(canvas, 'pointermove', (e) => {
      const d = this.#drag;
      if (!d) {
        if (e.buttons === 0) canvas.style.cursor = this.handleAt(e) ? 'move' : '';
        return;
      }
      if (d.face) return this.#dragFace(d, e);
      const per = (DRAG_SPEED * this.#diagonal()) / Math.max(1, canvas.clientHeight);
      this.setPlane({ ...this.plane, offset: d.offset + (d.y - e.clientY) * per });
    });
    const end = () => { this.#drag = null; };
    disposer.listen(canvas, 'pointerup', end);
    disposer.listen(canvas, 'pointercancel', end);
    disposer.add(() => cancelAnimationFrame(this.#raf));
  }

  // A new volume: the sliders span its box; a clip the state carries is shown.
  setVolume(volume, clip) {
    this.#volume = volume;
    const [lo, hi] = this.#box();
    this.ui.sliders.forEach((s, k) => {
      const a = k >> 1;
      Object.assign(s, { min: lo[a], max: hi[a], step: (hi[a] - lo[a]) / 200 || 1 });
    });
    const d = this.#diagonal() / 2;
    Object.assign(this.ui.offset, { min: -d, max: d, step: d / 200 || 1 });
    this.box = clip?.box ?? null;
    this.#kept = null;
    this.plane = null;
    if (clip?.plane) {
      const n = normalize(clip.plane.normal);
      this.plane = { normal: n, offset: dot(sub(clip.plane.point, this.#center()), n) };
    }
    this.#show();
  }

  // The crop box's faces: axis a, side 0 (low) or 1 (high), centre p (world).
  faces() {
    if (!this.box) return [];
    const c = this.box[0].map((l, a) => (l + this.box[1][a]) / 2), out = [];
    for (let a = 0; a < 3; a++)
      for (const side of [0, 1]) {
        const p = [...c];
        p[a] = this.box[side][a];
        out.push({ a, side, p });
      }
    return out;
  }

  // The face whose handle lies under a pointer event, with its screen position s; null: none.
  handleAt(e) {
    const r = this.canvas.getBoundingClientRect(), x = e.clientX - r.left, y = e.clientY - r.top;
    let best = null;
    for (const f of this.faces()) {
      const s = this.project(f.p);
      const d = s ? Math.hypot(s[0] - x, s[1] - y) : Infinity;
      if (d <= HANDLE_PX && (!best || d < best.d)) best = { ...f, s, d };
    }
    return best;
  }

  #dragFace(d, e) {
    const { a, side } = d.face, u = d.unit, uu = u[0] * u[0] + u[1] * u[1];
    if (!(uu > 1e-9)) return;  // the axis points at the viewer: its faces do not move sideways
    const move = ((e.clientX - d.x) * u[0] + (e.clientY - d.y) * u[1]) / uu;
    const [lo, hi] = this.#box();
    const box = this.box.map((c) => [...c]);
    box[side][a] = side === 0 ? Math.min(Math.max(d.value + move, lo[a]), box[1][a]) : Math.max(Math.min(d.value + move, hi[a]), box[0][a]);
    this.box = box;
    this.#sync();
  }

  setPlane(plane) {
    this.plane = plane;
    this.#sync();
  }

  // What goes into render.clip (null: no clip).
  get clip() {
    if (!this.box && !this.plane) return null;
    const c = {};
    if (this.box) c.box = this.box;
    if (this.plane) c.plane = { point: add(this.#center(), scale(this.plane.normal, this.plane.offset)), normal: this.plane.normal };
    return c;
  }

  #box() {
    const v = this.#volume;
    const lo = v.origin, hi = v.origin.map((o, a) => o + (v.dims[a] - 1) * v.spacing[a]);
    return [lo, hi];
  }

  #center() { const [lo, hi] = this.#box(); return lo.map((l, a) => (l + hi[a]) / 2); }
  #diagonal() { const [lo, hi] = this.#box(); return Math.hypot(...lo.map((l, a) => hi[a] - l)); }
  #bounds() { const [lo, hi] = this.#box(); return [[...lo], [...hi]]; }

  // The normal pointing away from the eye: the near half is cut away, the inside shows.
  #facing() {
    const c = this.camera.camera;
    return { normal: normalize(sub(c.center, c.eye)), offset: 0 };
  }

  #fromSliders() {
    const v = this.ui.sliders.map((s) => +s.value);
    const lo = [0, 1, 2].map((a) => Math.min(v[2 * a], v[2 * a + 1])), hi = [0, 1, 2].map((a) => Math.max(v[2 * a], v[2 * a + 1]));
    this.box = [lo, hi];
    this.ui.boxOn.checked = true;
    this.#sync();
  }

  #show() {
    const { ui } = this;
    ui.boxOn.checked = !!this.box;
    ui.planeOn.checked = !!this.plane;
    const box = this.box ?? this.#kept ?? this.#bounds();
    ui.sliders.forEach((s, k) => { s.value = box[k & 1][k >> 1]; });
    for (const el of [...ui.sliders]) el.disabled = !this.box;
    for (const el of [ui.offset, ui.flip]) el.disabled = !this.plane;
    if (this.plane) ui.offset.value = this.plane.offset;
    const parts = [];
    if (this.box) {
      const span = (a) => `${'xyz'[a]} ${+this.box[0][a].toPrecision(4)}…${+this.box[1][a].toPrecision(4)}`;
      parts.push(`box ${[0, 1, 2].map(span).join(', ')} ${this.unit}`);
    }
    if (this.plane) {
      parts.push(`plane normal (${this.plane.normal.map((n) => +n.toFixed(2)).join(', ')}), ` +
        `${formatLength(this.plane.offset, this.unit, 3)} from the centre`);
    }
    ui.readout.textContent = parts.join('; ');
  }

  #sync() {
    this.#show();
    if (this.#raf) return;
    this.#raf = requestAnimationFrame(() => {
      this.#raf = 0;
      this.dispatchEvent(new CustomEvent('change', { detail: this.clip }));
    });
  }
}

function axis(name) { return [0, 1, 2].map((a) => (AXES[a] === name ? 1 : 0)); }

// The polygon where the plane (point p, normal n) cuts the box [lo, hi]: for the annotations.
export function planeSection(lo, hi, p, n) {
  const corners = [];
  for (let i = 0; i < 8; i++) corners.push([i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]]);
  const side = corners.map((c) => dot(sub(c, p), n));
  const pts = [];
  for (let i = 0; i < 8; i++)
    for (const bit of [1, 2, 4]) {
      const j = i | bit;
      if (j === i || (side[i] > 0) === (side[j] > 0)) continue;
      const t = side[i] / (side[i] - side[j]);
      pts.push(add(corners[i], scale(sub(corners[j], corners[i]), t)));
    }
  if (pts.length < 3) return [];
  const c = scale(pts.reduce(add), 1 / pts.length);
  const u = normalize(sub(pts[0], c)), w = normalize([n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]]);
  return pts.sort((a, b) => Math.atan2(dot(sub(a, c), w), dot(sub(a, c), u)) - Math.atan2(dot(sub(b, c), w), dot(sub(b, c), u)));
}
