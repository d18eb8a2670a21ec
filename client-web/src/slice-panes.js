// Slice views beside the 3D view (the layout switch "3D + slices"): three axis-aligned slices
// through one point, drawn by the server (POST /api/slice, the TF's colours), each with a
// crosshair at the point. Clicking a slice moves the point there (the other two slices follow),
// the wheel steps a slice along its axis (Shift: 10 voxels), and a click in the 3D view moves the
// point to what was hit there (main.js, through the probe).
// Each slice is seen as the server draws it (docs/rest.md, "POST /api/slice"): from the axis'
// positive side, +y up (+z for the y slice), fitted into its pane with its world aspect kept.

// Per slice axis: the axis along the pane's right and its sign, the axis up the pane and its sign.
const FRAMES = { 0: { r: 2, rs: -1, u: 1, us: 1 }, 1: { r: 0, rs: -1, u: 2, us: 1 }, 2: { r: 0, rs: 1, u: 1, us: 1 } };
const NAMES = ['x', 'y', 'z'];

export class SlicePanes extends EventTarget {
  point = null;     // world
  info = null;      // the volume's info
  shown = false;
  #seq = [0, 0, 0];  // the newest request per pane: older answers are dropped
  #bitmaps = [null, null, null];
  #timer = 0;

  // panes: [{ canvas, caption }] for x, y, z; fetchSlice(body) -> Response; scene() -> the scene's
  // volume, tf, background, time.
  constructor({ root, panes }, { fetchSlice, scene }, disposer) {
    super();
    Object.assign(this, { root, panes, fetchSlice, scene });
    disposer.add(() => clearTimeout(this.#timer));
    panes.forEach((p, axis) => {
      disposer.listen(p.canvas, 'click', (e) => this.#click(axis, e));
      disposer.listen(p.canvas, 'wheel', (e) => { e.preventDefault(); this.step(axis, Math.sign(e.deltaY) * (e.shiftKey ? 10 : 1)); }, { passive: false });
    });
  }

  show(on) {
    this.shown = on;
    this.root.hidden = !on;
    if (on) this.refresh();
  }

  // A new volume: the point goes to its centre.
  setVolume(info) {
    this.info = info;
    const d = info.dims, s = info.spacing, o = info.origin;
    this.point = [0, 1, 2].map((a) => o[a] + ((d[a] - 1) * s[a]) / 2);
    this.refresh();
  }

  // The point, kept inside the volume's box; the slices that changed are drawn again.
  setPoint(p, only = [0, 1, 2]) {
    if (!this.info) return;
    const d = this.info.dims, s = this.info.spacing, o = this.info.origin;
    this.point = p.map((v, a) => Math.min(Math.max(v, o[a]), o[a] + (d[a] - 1) * s[a]));
    this.dispatchEvent(new CustomEvent('point', { detail: this.point }));
    this.refresh(only);
  }

  step(axis, voxels) {
    if (!this.point) return;
    const p = [...this.point];
    p[axis] += voxels * this.#fullSpacing(axis);
    this.setPoint(p, [axis]);
  }

  // The index along `axis` of the point, in the volume's full-resolution voxels.
  index(axis) {
    return Math.round((this.point[axis] - this.info.origin[axis]) / this.#fullSpacing(axis));
  }

  // After an edit that may come many times a second (a TF drag): once it rests for 150 ms.
  refreshSoon() {
    clearTimeout(this.#timer);
    this.#timer = setTimeout(() => this.refresh(), 150);
  }

  refresh(only = [0, 1, 2]) {
    if (!this.shown || !this.info || !this.point) return;
    for (const axis of [0, 1, 2]) {
      if (only.includes(axis)) this.#load(axis);
      else this.#draw(axis);  // only the crosshair moved
    }
  }

  #fullSpacing(axis) {
    const d = this.info.dims[axis], f = this.info.full_dims?.[axis] ?? d;
    return f > 1 ? (this.info.spacing[axis] * (d - 1)) / (f - 1) : this.info.spacing[axis];
  }

  async #load(axis) {
    const pane = this.panes[axis], seq = ++this.#seq[axis];
    const dpr = Math.min(window.devicePixelRatio || 1, 2);
    const width = Math.max(16, Math.round(pane.canvas.clientWidth * dpr)), height = Math.max(16, Math.round(pane.canvas.clientHeight * dpr));
    const index = this.index(axis);
    const body = { ...this.scene(), image: { width, height }, slice: { axis: NAMES[axis], index } };
    try {
      const res = await this.fetchSlice(body);
      if (!res.ok) throw new Error((await res.json().catch(() => ({}))).message ?? `HTTP ${res.status}`);
      const bitmap = await createImageBitmap(await res.blob());
      if (seq !== this.#seq[axis]) return bitmap.close();  // a newer slice was asked for
      this.#bitmaps[axis]?.close();
      this.#bitmaps[axis] = bitmap;
      Object.assign(pane.canvas, { width, height });
      pane.canvas.dataset.index = String(index);
      pane.canvas.dataset.loads = String((+pane.canvas.dataset.loads || 0) + 1);
      this.#draw(axis);
    } catch (e) {
      if (seq === this.#seq[axis]) pane.caption.textContent = `${NAMES[axis]}: ${e.message}`;
    }
  }

  // The pane's frame: world coordinate of its pixel (col, row) along its right and up axes.
  #frame(axis) {
    const { r, rs, u, us } = FRAMES[axis], c = this.panes[axis].canvas;
    const d = this.info.dims, s = this.info.spacing;
    const span = (a, sign) => { const last = sign * (d[a] - 1) * s[a]; return [Math.min(0, last) - s[a] / 2, Math.max(0, last) + s[a] / 2]; };
    const [u0, u1] = span(r, rs), [v0, v1] = span(u, us);
    const px = Math.max((u1 - u0) / c.width, (v1 - v0) / c.height);
    return { r, rs, u, us, px, cu: (u0 + u1) / 2 - (px * c.width) / 2, cv: (v0 + v1) / 2 + (px * c.height) / 2 };
  }

  // Where the point lies in pane `axis` (canvas pixels).
  pixelOf(axis, p = this.point) {
    const f = this.#frame(axis), o = this.info.origin;
    return [(f.rs * (p[f.r] - o[f.r]) - f.cu) / f.px, (f.cv - f.us * (p[f.u] - o[f.u])) / f.px];
  }

  #draw(axis) {
    const pane = this.panes[axis], c = pane.canvas, g = c.getContext('2d'), bitmap = this.#bitmaps[axis];
    if (!bitmap) return;
    g.drawImage(bitmap, 0, 0, c.width, c.height);
    const [x, y] = this.pixelOf(axis);
    g.strokeStyle = '#fd4';
    g.lineWidth = 1;
    g.beginPath();
    g.moveTo(0, y + 0.5); g.lineTo(c.width, y + 0.5);
    g.moveTo(x + 0.5, 0); g.lineTo(x + 0.5, c.height);
    g.stroke();
    pane.caption.textContent = `${NAMES[axis]} = ${this.index(axis)}`;
  }

  #click(axis, e) {
    if (!this.point) return;
    const c = this.panes[axis].canvas, rect = c.getBoundingClientRect();
    const col = ((e.clientX - rect.left) * c.width) / rect.width, row = ((e.clientY - rect.top) * c.height) / rect.height;
    const f = this.#frame(axis), o = this.info.origin, p = [...this.point];
    p[f.r] = o[f.r] + f.rs * (f.cu + col * f.px);
    p[f.u] = o[f.u] + f.us * (f.cv - row * f.px);
    this.setPoint(p, [0, 1, 2].filter((a) => a !== axis));
  }
}
