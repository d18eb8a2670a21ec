// Probing (proto/messages.md, "Probes"): the data value and world position under the cursor,
// asked of the server as the pointer rests or moves (one question per animation frame; only the
// newest answer is shown), and a two-point distance: with "measure" on, a click fixes a point, a
// second click the other, and the distance between them is shown (and drawn by the annotations).
// The server answers at the ray's first visible surface (the first sample its TF makes at least
// 5% opaque: a click on a translucent edge lands on its front), or with `pick` 'half' where the
// ray gets half opaque; the readout says which point it is.
import { formatLength } from './units.js';
import { length, sub } from './vec.js';

const CLICK_PX = 4;  // a press that moves less than this is a click, not a drag
const PICKS = { surface: 'first surface', half: 'half opacity' };  // the answer's pick, as the readout says it

export class Probe extends EventTarget {
  #id = 0;
  #raf = 0;
  #at = null;           // the pointer's device pixel, to probe at the next animation frame
  #hover = 0;           // id of the newest hover probe
  #clicks = new Set();  // ids of probes that fix a measure point
  #picks = new Set();   // ids of probes that pick a point for the slice views
  picking = () => false;  // whether a click, not measuring, picks a point ('pick' event)
  #down = null;
  #unavailable = '';
  last = null;          // the newest hover answer
  points = [];          // measure points (world), at most two
  picks = [];           // the pick that answered each of them
  unit = 'units';       // lengths' unit (units.js)
  measuring = false;
  pick = 'surface';     // 'surface' | 'half': the point along the ray that answers

  constructor({ canvas, readout, measure, pick, stream }, disposer) {
    super();
    Object.assign(this, { canvas, readout, measureButton: measure, stream });
    if (pick) disposer.listen(pick, 'change', () => { this.pick = pick.value; this.points = []; this.picks = []; this.#changed(); });
    disposer.listen(canvas, 'pointermove', (e) => { if (e.buttons === 0 && e.pointerType !== 'touch') this.#schedule(e); });
    disposer.listen(canvas, 'pointerleave', () => { this.#at = null; this.#show(); });
    disposer.listen(canvas, 'pointerdown', (e) => { this.#down = { x: e.clientX, y: e.clientY }; });
    disposer.listen(canvas, 'pointerup', (e) => this.#up(e));
    disposer.listen(measure, 'click', () => this.setMeasuring(!this.measuring));
    disposer.listen(stream, 'probe', (e) => this.#answer(e.detail));
    disposer.add(() => cancelAnimationFrame(this.#raf));
  }

  setMeasuring(on) {
    this.measuring = on;
    this.measureButton.setAttribute('aria-pressed', String(on));
    if (!on) this.points = [];
    this.#changed();
  }

  // Another volume: the measure starts again.
  reset() {
    this.points = [];
    this.last = null;
    this.#changed();
  }

  // A refused probe. Where the server cannot probe at all (a volume held in MPI bricks) that is
  // said once and no more questions go; a pixel the server's viewport no longer has (a resize
  // under way) is only skipped.
  failed(message) {
    if (!/voxels/.test(message)) return;
    this.#unavailable = message.replace(/^probe: /, '');
    this.#show();
  }

  // Device pixel of a pointer event, inside the view (what the server's viewport counts).
  pixelOf(e) {
    const r = this.canvas.getBoundingClientRect(), dpr = Math.min(window.devicePixelRatio || 1, 4);
    const w = Math.max(1, Math.round(r.width * dpr)), h = Math.max(1, Math.round(r.height * dpr));
    const clamp = (v, n) => Math.min(n - 1, Math.max(0, Math.floor(v)));
    return [clamp((e.clientX - r.left) * dpr, w), clamp((e.clientY - r.top) * dpr, h)];
  }

  #ask(pixel) {
    if (this.#unavailable) return 0;
    const id = ++this.#id;
    this.stream.send({ type: 'probe', id, pixel, pick: this.pick });
    return id;
  }

  #schedule(e) {
    this.#at = this.pixelOf(e);
    if (this.#raf) return;
    this.#raf = requestAnimationFrame(() => {
      this.#raf = 0;
      if (this.#at) this.#hover = this.#ask(this.#at);
    });
  }

  #up(e) {
    const d = this.#down;
    this.#down = null;
    if (!d || Math.hypot(e.clientX - d.x, e.clientY - d.y) >= CLICK_PX) return;
    if (!this.measuring && !this.picking()) return;
    const id = this.#ask(this.pixelOf(e));
    if (id) (this.measuring ? this.#clicks : this.#picks).add(id);
  }

  #answer(a) {
    if (this.#picks.delete(a.id)) {
      if (a.hit) this.dispatchEvent(new CustomEvent('pick', { detail: a.position }));
      return;
    }
    if (this.#clicks.delete(a.id)) {
      if (!a.hit) return this.#note('nothing opaque there to measure from');
      this.points = this.points.length >= 2 ? [a.position] : [...this.points, a.position];
      this.picks = this.points.length === 1 ? [a.pick] : [...this.picks, a.pick];
      return this.#changed();
    }
    if (a.id !== this.#hover) return;  // an older answer: the cursor moved on
    this.last = a;
    this.#show();
  }

  get distance() { return this.points.length === 2 ? length(sub(this.points[1], this.points[0])) : null; }

  #changed() {
    this.#show();
    this.dispatchEvent(new CustomEvent('points', { detail: this.points }));
  }

  #note(text) {
    this.readout.textContent = text;
    this.readout.hidden = false;
  }

  #show() {
    const parts = [];
    if (this.#unavailable) parts.push(`probing unavailable: ${this.#unavailable}`);
    else if (this.#at && this.last) {
      const a = this.last;
      parts.push(a.hit ? `value ${fmt(a.value)} at (${a.position.map(fmt).join(', ')}) ${this.unit} (${PICKS[a.pick] ?? a.pick})`
        : 'nothing opaque under the cursor');
    }
    if (this.measuring) {
      const [p, q] = this.points;
      if (!p) parts.push('measure: click a first point');
      else if (!q) parts.push(`measure: from (${p.map(fmt).join(', ')}) ${this.unit}, click a second point`);
      else parts.push(`distance ${formatLength(this.distance, this.unit)} (${[...new Set(this.picks)].map((k) => PICKS[k] ?? k).join(', ')})`);
    }
    this.readout.textContent = parts.join(' · ');
    this.readout.hidden = parts.length === 0;
    this.readout.dataset.distance = this.distance === null ? '' : String(this.distance);
  }
}

function fmt(v) { return String(+v.toPrecision(4)); }
