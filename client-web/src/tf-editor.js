// The transfer-function editor: the volume's histogram (log scale) under the piecewise-linear
// opacity curve; add, drag, delete points, a colour per point, detected peaks marked, presets,
// undo/redo, keyboard control. Every edit emits the full TF with a new version; a drag emits at
// most one per animation frame (the newest), however fast the pointer moves.
import { COLORMAPS, findPeaks, interpolate, preset, PRESET_NEEDS, TfHistory } from './tf-model.js';

const hex = (rgb) => '#' + rgb.map((c) => Math.round(c * 255).toString(16).padStart(2, '0')).join('');
const rgbOf = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16) / 255);

export class TfEditor extends EventTarget {
  points = [];
  version = 1;
  logHistogram = true;  // the histogram's vertical axis: log counts (else linear)
  selected = -1;
  #history = new TfHistory();
  #drag = null;
  #frameRequest = 0;  // a coalesced emit waiting for the next animation frame

  constructor(ui, disposer) {
    super();
    this.ui = ui;
    this.canvas = ui.canvas;
    this.ctx = this.canvas.getContext('2d');
    const c = this.canvas;
    disposer.listen(c, 'pointerdown', (e) => this.#down(e));
    disposer.listen(c, 'pointermove', (e) => this.#move(e));
    disposer.listen(c, 'pointerup', () => this.#up());
    disposer.listen(c, 'pointercancel', () => this.#up());  // the browser took the gesture: the drag ends here
    disposer.listen(c, 'keydown', (e) => this.#key(e));
    disposer.add(() => cancelAnimationFrame(this.#frameRequest));
    disposer.listen(c, 'dblclick', (e) => this.#remove(this.#hit(e)));
    disposer.listen(ui.color, 'input', () => this.#recolor());
    disposer.listen(ui.remove, 'click', () => this.#remove(this.selected));
    disposer.listen(ui.undo, 'click', () => this.#restore(this.#history.undo(this.points)));
    disposer.listen(ui.redo, 'click', () => this.#restore(this.#history.redo(this.points)));
    disposer.listen(ui.preset, 'change', () => this.applyPreset(ui.preset.value));
    // The isovalue follows its box while the isosurface preset is the TF.
    disposer.listen(ui.iso, 'input', () => { if (ui.preset.value === 'iso' && Number.isFinite(parseFloat(ui.iso.value))) this.applyPreset('iso'); });
  }

  setVolume(info) {
    this.lo = info.range[0];
    this.hi = info.range[1] > info.range[0] ? info.range[1] : info.range[0] + 1;
    this.histogram = info.histogram || [];
    this.inHu = info.value_unit === 'HU';  // the CT presets' values are Hounsfield units
    this.ui.iso.value = ((this.lo + this.hi) / 2).toPrecision(5);
  }

  // Keeps `points` as the state undo returns to (the TF a new volume replaced).
  remember(points) { this.#history.push(points); }

  // A TF from a tool (window/level, a file): an edit the user can undo.
  apply(points) {
    this.#history.push(this.points);
    this.set(points, { silent: false });
  }

  set(points, { silent = true } = {}) {
    this.points = structuredClone(points);
    this.selected = -1;
    this.ui.preset.value = '';  // a TF from elsewhere (the server, undo, a file) is no preset
    this.draw();
    if (!silent) this.#emit();
  }

  // The preset stays shown in its menu until the TF is edited by hand. A preset that needs a
  // classification says so ('preset' event: {classification, shading}).
  applyPreset(name) {
    const p = preset(name, this.lo, this.hi, parseFloat(this.ui.iso.value), this.inHu, this.histogram);
    if (!p) {
      this.ui.preset.value = '';
      return;
    }
    this.#history.push(this.points);
    this.set(p, { silent: false });
    this.ui.preset.value = name;
    // A colour map is an opacity ramp, with no peak to find: peak finding gives way to
    // pre-integration (other classifications stay).
    const needs = PRESET_NEEDS[name] ?? (COLORMAPS[name] ? { classification: 'preint', unlessNot: 'peaks' } : null);
    if (needs) this.dispatchEvent(new CustomEvent('preset', { detail: needs }));
  }

  // Canvas geometry: x = value over [lo, hi], y = opacity.
  #x(v) { return ((v - this.lo) / (this.hi - this.lo)) * this.canvas.width; }
  #y(a) { return (1 - a) * (this.canvas.height - 10) + 5; }
  #value(x) { return this.lo + (x / this.canvas.width) * (this.hi - this.lo); }
  #alpha(y) { return Math.min(1, Math.max(0, 1 - (y - 5) / (this.canvas.height - 10))); }
  #pos(e) {
    const r = this.canvas.getBoundingClientRect();
    return { x: ((e.clientX - r.left) * this.canvas.width) / r.width, y: ((e.clientY - r.top) * this.canvas.height) / r.height };
  }
  #hit(e) {
    const p = this.#pos(e);
    return this.points.findIndex((q) => Math.hypot(this.#x(q[0]) - p.x, this.#y(q[4]) - p.y) < 7);
  }

  #down(e) {
    let i = this.#hit(e);
    this.#history.push(this.points);
    this.ui.preset.value = '';
    if (i < 0) {  // add a point with the colour the curve has there
      const p = this.#pos(e), v = this.#value(p.x);
      const c = interpolate(this.points, v);
      i = this.points.findIndex((q) => q[0] > v);
      if (i < 0) i = this.points.length;
      this.points.splice(i, 0, [v, c[0], c[1], c[2], this.#alpha(p.y)]);
      this.#emit();
    }
    this.selected = i;
    this.ui.color.value = hex(this.points[i].slice(1, 4));
    this.#drag = { index: i };
    this.canvas.setPointerCapture(e.pointerId);
    this.draw();
    this.#announce();
  }

  #move(e) {
    if (!this.#drag) return;
    const p = this.#pos(e), i = this.#drag.index, pts = this.points;
    const lo = i > 0 ? pts[i - 1][0] : this.lo - (this.hi - this.lo);
    const hi = i + 1 < pts.length ? pts[i + 1][0] : this.hi + (this.hi - this.lo);
    pts[i][0] = Math.min(hi, Math.max(lo, this.#value(p.x)));
    pts[i][4] = this.#alpha(p.y);
    this.draw();
    this.#emitSoon();
  }

  #up() {
    this.#drag = null;
    this.#flush();  // the drag's last position goes out now, not a frame later
  }

  // Keyboard: PageDown/PageUp (or n/p) select the next/previous point, arrows move it (value by
  // 1% of the range, opacity by 0.02; Shift: 10x), Delete/Backspace remove it, Ctrl+Z undoes and
  // Ctrl+Shift+Z or Ctrl+Y redoes (Cmd on a Mac).
  #key(e) {
    if ((e.ctrlKey || e.metaKey) && (e.key === 'z' || e.key === 'Z' || e.key === 'y')) {  // as the buttons
      const redo = e.key === 'y' || e.shiftKey;
      this.#restore(redo ? this.#history.redo(this.points) : this.#history.undo(this.points));
      e.preventDefault();
      return;
    }
    const n = this.points.length;
    if (!n) return;
    const big = e.shiftKey ? 10 : 1;
    let i = this.selected;
    if (e.key === 'PageDown' || e.key === 'n') i = i < 0 ? 0 : Math.min(n - 1, i + 1);
    else if (e.key === 'PageUp' || e.key === 'p') i = i < 0 ? n - 1 : Math.max(0, i - 1);
    else if (e.key === 'Delete' || e.key === 'Backspace') { this.#remove(i); this.#announce(); e.preventDefault(); return; }
    else if (i >= 0 && e.key.startsWith('Arrow')) {
      this.#history.push(this.points);
      this.ui.preset.value = '';
      const p = this.points[i], span = this.hi - this.lo;
      if (e.key === 'ArrowLeft' || e.key === 'ArrowRight') {
        const lo = i > 0 ? this.points[i - 1][0] : this.lo - span, hi = i + 1 < n ? this.points[i + 1][0] : this.hi + span;
        p[0] = Math.min(hi, Math.max(lo, p[0] + (e.key === 'ArrowRight' ? 1 : -1) * 0.01 * big * span));
      } else {
        p[4] = Math.min(1, Math.max(0, p[4] + (e.key === 'ArrowUp' ? 1 : -1) * 0.02 * big));
      }
      this.draw();
      this.#emitSoon();
    } else return;
    e.preventDefault();
    if (i !== this.selected) {
      this.selected = i;
      this.ui.color.value = hex(this.points[i].slice(1, 4));
      this.draw();
    }
    this.#announce();
  }

  #announce() {
    const p = this.points[this.selected];
    if (this.ui.point) this.ui.point.textContent = p ? `point ${this.selected + 1} of ${this.points.length}: value ${p[0].toPrecision(5)}, opacity ${p[4].toFixed(2)}` : '';
  }

  // The end points stay: they set the TF beyond the data's range (move them instead).
  #remove(i) {
    if (i <= 0 || i >= this.points.length - 1) return;
    this.#history.push(this.points);
    this.points.splice(i, 1);
    this.selected = -1;
    this.draw();
    this.#emit();
  }

  #recolor() {
    if (this.selected < 0) return;
    this.#history.push(this.points);
    const [r, g, b] = rgbOf(this.ui.color.value);
    Object.assign(this.points[this.selected], { 1: r, 2: g, 3: b });
    this.draw();
    this.#emit();
  }

  #restore(points) { if (points) this.set(points, { silent: false }); }

  #emitSoon() {
    if (!this.#frameRequest) this.#frameRequest = requestAnimationFrame(() => { this.#frameRequest = 0; this.#emit(); });
  }

  #flush() { if (this.#frameRequest) this.#emit(); }

  #emit() {
    cancelAnimationFrame(this.#frameRequest);  // this emit carries the newest points
    this.#frameRequest = 0;
    this.version++;
    this.dispatchEvent(new CustomEvent('change', { detail: { points: structuredClone(this.points), version: this.version } }));
  }

  draw() {
    this.#announce();  // the readout shows what is drawn: never one edit behind
    this.dispatchEvent(new Event('drawn'));
    const { ctx, canvas } = this, w = canvas.width, h = canvas.height;
    ctx.clearRect(0, 0, w, h);
    if (this.histogram?.length) {  // log or linear counts
      const f = this.logHistogram ? Math.log1p : (n) => n;
      const max = f(Math.max(...this.histogram)) || 1;
      ctx.fillStyle = '#334';
      const bw = w / this.histogram.length;
      this.histogram.forEach((n, i) => {
        const bh = (f(n) / max) * (h - 10);
        ctx.fillRect(i * bw, h - bh, Math.ceil(bw), bh);
      });
    }
    if (!this.points.length) return;
    const grad = ctx.createLinearGradient(0, 0, w, 0);
    for (const p of this.points) {
      const t = Math.min(1, Math.max(0, (p[0] - this.lo) / (this.hi - this.lo)));
      grad.addColorStop(t, hex(p.slice(1, 4)));
    }
    ctx.beginPath();
    ctx.moveTo(0, this.#y(this.points[0][4]));
    for (const p of this.points) ctx.lineTo(this.#x(p[0]), this.#y(p[4]));
    ctx.lineTo(w, this.#y(this.points[this.points.length - 1][4]));
    ctx.strokeStyle = '#ddd';
    ctx.stroke();
    ctx.lineTo(w, h);
    ctx.lineTo(0, h);
    ctx.globalAlpha = 0.35;
    ctx.fillStyle = grad;
    ctx.fill();
    ctx.globalAlpha = 1;
    this.points.forEach((p, i) => {
      ctx.beginPath();
      ctx.arc(this.#x(p[0]), this.#y(p[4]), i === this.selected ? 6 : 4, 0, 2 * Math.PI);
      ctx.fillStyle = hex(p.slice(1, 4));
      ctx.fill();
      ctx.strokeStyle = i === this.selected ? '#fff' : '#888';
      ctx.stroke();
    });
    ctx.fillStyle = '#f44';
    for (const v of findPeaks(this.points)) {  // the peaks peak finding will render as surfaces
      const x = this.#x(v);
      ctx.beginPath();
      ctx.moveTo(x, h - 1);
      ctx.lineTo(x - 5, h - 9);
      ctx.lineTo(x + 5, h - 9);
      ctx.fill();
    }
  }
}
