// Camera interaction: orbit (left drag / one finger), pan (right or shift drag / two fingers),
// zoom (wheel / pinch). Changes are coalesced to one message per animation frame (<= 60 Hz).
import { add, cross, length, normalize, rotate, scale, sub } from './vec.js';

export class CameraController extends EventTarget {
  camera = null;   // {eye, center, up, fov_y | projection+height}
  home = null;     // the view to reset to
  #dirty = false;
  #raf = 0;
  #drag = null;
  #touches = new Map();
  ignore = () => false;  // (pointerdown) => true: another tool takes that drag (the brush in paint mode)

  constructor(element, disposer) {
    super();
    this.el = element;
    disposer.listen(element, 'pointerdown', (e) => this.#down(e));
    disposer.listen(element, 'pointermove', (e) => this.#move(e));
    disposer.listen(element, 'pointerup', (e) => this.#up(e));
    disposer.listen(element, 'pointercancel', (e) => this.#up(e));
    disposer.listen(element, 'wheel', (e) => this.#wheel(e), { passive: false });
    disposer.listen(element, 'contextmenu', (e) => e.preventDefault());
    disposer.add(() => cancelAnimationFrame(this.#raf));
  }

  set(camera, { home = false, silent = false } = {}) {
    this.camera = structuredClone(camera);
    if (home || !this.home) this.home = structuredClone(camera);
    if (!silent) this.#changed();
  }

  reset() { if (this.home) this.set(this.home); }

  // Axis-aligned views keep the distance to the centre.
  view(axis) {
    if (axis === 'reset') return this.reset();
    const c = this.camera, d = length(sub(c.eye, c.center));
    const dirs = { '+x': [1, 0, 0], '-x': [-1, 0, 0], '+y': [0, 1, 0], '-y': [0, -1, 0], '+z': [0, 0, 1], '-z': [0, 0, -1] };
    const dir = dirs[axis];
    const up = axis.endsWith('z') ? [0, 1, 0] : [0, 0, 1];
    this.set({ ...c, eye: add(c.center, scale(dir, d)), up });
  }

  #changed() {
    this.#dirty = true;
    if (!this.#raf) this.#raf = requestAnimationFrame(() => {
      this.#raf = 0;
      if (this.#dirty) { this.#dirty = false; this.dispatchEvent(new CustomEvent('change', { detail: this.camera })); }
    });
  }

  #frame() {
    const c = this.camera;
    const forward = normalize(sub(c.center, c.eye));
    const right = normalize(cross(forward, c.up));
    const up = cross(right, forward);
    return { forward, right, up, dist: length(sub(c.eye, c.center)) };
  }

  orbit(dx, dy) {
    const c = this.camera, f = this.#frame();
    const k = Math.PI / Math.max(200, this.el.clientHeight);
    let offset = sub(c.eye, c.center), up = f.up;
    offset = rotate(offset, f.up, -dx * k);
    const right = normalize(cross(scale(offset, -1), f.up));
    offset = rotate(offset, right, -dy * k);
    up = rotate(up, right, -dy * k);
    this.camera = { ...c, eye: add(c.center, offset), up };
    this.#changed();
  }

  pan(dx, dy) {
    const c = this.camera, f = this.#frame();
    const h = c.projection === 'orthographic' ? c.height : 2 * f.dist * Math.tan(((c.fov_y ?? 30) * Math.PI) / 360);
    const perPixel = h / Math.max(1, this.el.clientHeight);
    const move = add(scale(f.right, -dx * perPixel), scale(f.up, dy * perPixel));
    this.camera = { ...c, eye: add(c.eye, move), center: add(c.center, move) };
    this.#changed();
  }

  zoom(factor) {
    const c = this.camera;
    if (c.projection === 'orthographic') this.camera = { ...c, height: c.height * factor };
    else this.camera = { ...c, eye: add(c.center, scale(sub(c.eye, c.center), factor)) };
    this.#changed();
  }

  #down(e) {
    if (!this.camera || this.ignore(e)) return;
    this.el.setPointerCapture(e.pointerId);
    if (e.pointerType === 'touch') { this.#touches.set(e.pointerId, { x: e.clientX, y: e.clientY }); return; }
    this.#drag = { x: e.clientX, y: e.clientY, pan: e.button === 2 || e.button === 1 || e.shiftKey };
  }

  #move(e) {
    if (e.pointerType === 'touch' && this.#touches.has(e.pointerId)) return this.#touchMove(e);
    if (!this.#drag) return;
    const dx = e.clientX - this.#drag.x, dy = e.clientY - this.#drag.y;
    this.#drag.x = e.clientX;
    this.#drag.y = e.clientY;
    if (this.#drag.pan) this.pan(dx, dy); else this.orbit(dx, dy);
  }

  #touchMove(e) {
    const before = [...this.#touches.values()];
    this.#touches.set(e.pointerId, { x: e.clientX, y: e.clientY });
    const after = [...this.#touches.values()];
    if (after.length === 1) return this.orbit(after[0].x - before[0].x, after[0].y - before[0].y);
    const mid = (p) => ({ x: (p[0].x + p[1].x) / 2, y: (p[0].y + p[1].y) / 2 });
    const span = (p) => Math.hypot(p[0].x - p[1].x, p[0].y - p[1].y);
    const m0 = mid(before), m1 = mid(after);
    this.pan(m1.x - m0.x, m1.y - m0.y);
    if (span(after) > 0) this.zoom(span(before) / span(after));
  }

  #up(e) {
    this.#touches.delete(e.pointerId);
    this.#drag = null;
  }

  #wheel(e) {
    if (!this.camera) return;
    e.preventDefault();
    this.zoom(Math.exp(e.deltaY * 0.001));
  }
}
