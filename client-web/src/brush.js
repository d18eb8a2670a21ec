// The ray-texture brush: a paint mode beside orbit. In paint mode a left drag (one
// finger) paints strokes: one where the pointer goes down and one every half radius along its
// path; shift / right drags and the wheel still move the camera. Each stroke joins the client's
// list (ray-texture-model.js), goes to the server (ray-texture-sync.js) and shows in the preview.
// Mapping view: a stroke sits at the pixel under the pointer; volume: at the texel the ray
// through that pixel reads (its entry point on the volume box, ray-texture-mapping.js).
import { BrushControls } from './brush-controls.js';
import { volumeUv, viewUv } from './ray-texture-mapping.js';
import { DEFAULT_TERMINATION, RayTextureModel } from './ray-texture-model.js';
import { BrushOutline, LEGENDS, TexturePreview } from './ray-texture-overlay.js';
import { RayTextureSync } from './ray-texture-sync.js';

const LONG_SIDE = 256;  // texels along the texture's longer side
const round = (x) => Math.round(x * 1e5) / 1e5;
const strokes = (n) => `${n} stroke${n === 1 ? '' : 's'}`;

export class Brush extends EventTarget {
  caps = null;        // capabilities.ray_texture, or null: no paint UI
  termination = DEFAULT_TERMINATION;
  note = '';          // the last thing worth saying (a mapping switch cleared the strokes, ...)
  #drag = null;       // {id, last, carry}: a paint drag
  #drags = [];        // the stroke count where each drag began: undo takes back a whole drag
  #pointer = null;    // the pointer over the image, for the outline
  #raf = 0;

  // ui: section, controls, canvas, view, outline, previewBox, preview, legend, status, undo, clear.
  // scene(): {camera, volume} (the volume's info) for the volume mapping.
  constructor(ui, { stream, camera, scene }, disposer) {
    super();
    this.ui = ui;
    this.scene = scene;
    this.sync = new RayTextureSync(stream);
    this.controls = new BrushControls(ui.controls, disposer);
    this.preview = new TexturePreview(ui.preview);
    this.outline = new BrushOutline(ui.outline);
    camera.ignore = (e) => this.painting && e.button === 0 && !e.shiftKey;  // that drag paints
    disposer.add(() => { camera.ignore = () => false; });
    disposer.add(() => this.sync.dispose());
    disposer.add(() => cancelAnimationFrame(this.#raf));
    disposer.listen(this.sync, 'change', () => this.#redrawSoon());
    disposer.listen(this.controls, 'change', (e) => this.#setting(e.detail));
    disposer.listen(ui.undo, 'click', () => this.undo());
    disposer.listen(ui.clear, 'click', () => this.clear());
    const c = ui.canvas;
    disposer.listen(c, 'pointerdown', (e) => this.#down(e));
    disposer.listen(c, 'pointermove', (e) => this.#move(e));
    disposer.listen(c, 'pointerup', (e) => this.#up(e));
    disposer.listen(c, 'pointercancel', (e) => this.#up(e));
    disposer.listen(c, 'pointerleave', () => { this.#pointer = null; this.#redrawSoon(); });
  }

  get painting() { return this.caps !== null && this.controls.settings.drag === 'paint'; }
  get model() { return this.sync.model; }

  // The hello's render.ray_texture (null: none), on every (re)connection.
  helloSpec() { return this.sync.helloSpec(); }

  welcome(capabilities, state) {
    const caps = capabilities?.ray_texture;
    this.caps = caps && typeof caps === 'object' ? caps : null;
    this.ui.section.hidden = !this.caps;
    this.setTermination(state.render?.early_termination);
    const server = state.render?.ray_texture ?? null;
    if (!this.caps) {
      this.sync.forget();  // this server takes no ray textures
    } else {
      this.controls.build(this.caps);
      if (!this.model && server?.size && server.strokes?.length) {  // the session has a texture the page does not: show it
        const m = new RayTextureModel({ mapping: server.mapping, width: server.size[0], height: server.size[1], termination: this.termination, ranges: this.caps.channels });
        for (const s of server.strokes) m.push(s);
        this.sync.adopt(m);
      }
    }
    this.sync.welcome(server);
    this.#applyDrag();
  }

  // A volume switch: the server keeps the texture; should it not, it gets ours again.
  volumeChanged(state) {
    this.setTermination(state.render?.early_termination);
    if (this.model && !state.render?.ray_texture) this.sync.replace(this.model);
  }

  setTermination(t) {
    if (!Number.isFinite(t) || t === this.termination) return;
    this.termination = t;
    if (this.model) { this.model.termination = Math.min(1, Math.max(0, t)); this.model.rebuild(); }
    this.#redrawSoon();
  }

  // For a REST still of the same view: the texture, when it fits a request body.
  sceneRender() {
    if (!this.model) return {};
    const spec = this.model.spec();
    return JSON.stringify(spec).length < 900 * 1024 ? { ray_texture: spec } : {};
  }

  undo() {
    const m = this.model;
    if (!m?.strokes.length) return;
    // Back to where the last drag began (strokes the page did not paint, restored from the
    // session, go one at a time).
    let start = m.strokes.length - 1;
    while (this.#drags.length && this.#drags.at(-1) >= m.strokes.length) this.#drags.pop();
    if (this.#drags.length) start = this.#drags.pop();
    m.truncate(start);
    this.note = '';
    this.sync.replace(m);
  }

  clear() {
    if (!this.model) return;
    this.note = this.model.strokes.length ? `cleared ${strokes(this.model.strokes.length)}` : '';
    this.#drags = [];
    this.sync.replace(this.#newModel(this.model.mapping));
  }

  #newModel(mapping) {
    const r = this.ui.canvas.getBoundingClientRect(), max = this.caps?.max_size ?? 2048, long = Math.min(LONG_SIDE, max);
    let w = long, h = long;
    if (mapping === 'volume') [w, h] = [Math.min(2 * long, max), long];  // u runs around the box, v pole to pole
    else if (r.width >= r.height) h = Math.max(1, Math.round((long * r.height) / Math.max(1, r.width)));  // texels as square as pixels
    else w = Math.max(1, Math.round((long * r.width) / Math.max(1, r.height)));
    return new RayTextureModel({ mapping, width: w, height: h, termination: this.termination, ranges: this.caps?.channels });
  }

  #setting({ key, value }) {
    if (key === 'drag') this.#applyDrag();
    if (key === 'mapping' && this.model && this.model.mapping !== value) {
      const n = this.model.strokes.length;
      this.note = n ? `mapping ${value}: ${strokes(n)} cleared` : '';
      this.#drags = [];
      this.sync.replace(this.#newModel(value));
    }
    this.#redrawSoon();
  }

  #applyDrag() {
    const paint = this.painting;
    this.ui.view.classList.toggle('painting', paint);
    this.ui.outline.hidden = !paint;
    if (!paint) this.#drag = null;
    if (paint && !this.model) this.sync.replace(this.#newModel(this.controls.settings.mapping));  // the session's texture, empty
    this.#redrawSoon();
  }

  #pos(e) {
    const rect = this.ui.canvas.getBoundingClientRect();
    return { x: e.clientX - rect.left, y: e.clientY - rect.top, rect };
  }

  #uv(p, mapping = this.model?.mapping) {
    const fx = p.x / p.rect.width, fy = p.y / p.rect.height;
    if (mapping !== 'volume') return viewUv(fx, fy);
    const { camera, volume } = this.scene();
    return camera && volume ? volumeUv(camera, volume, fx, fy, p.rect.width / p.rect.height) : null;
  }

  #down(e) {
    if (!this.painting || e.button !== 0 || e.shiftKey || !this.model) return;
    this.ui.canvas.setPointerCapture(e.pointerId);
    const p = this.#pos(e);
    this.#drag = { id: e.pointerId, last: p, carry: 0 };
    this.#drags.push(this.model.strokes.length);
    this.#pointer = p;
    this.#stamp(p);
  }

  // Strokes every half radius (in image pixels) along the path, however far apart the events.
  #move(e) {
    if (!this.painting) return;
    const p = this.#pos(e);
    this.#pointer = p;
    const d = this.#drag;
    if (d && e.pointerId === d.id) {
      const m = this.model, side = Math.max(m.width, m.height);
      const radiusPx = Math.min((this.controls.settings.radius * side * p.rect.width) / m.width, (this.controls.settings.radius * side * p.rect.height) / m.height);
      const spacing = Math.max(1, radiusPx / 2);
      let from = d.last, left = Math.hypot(p.x - from.x, p.y - from.y), travelled = d.carry;
      while (travelled + left >= spacing) {
        const t = (spacing - travelled) / left;
        from = { x: from.x + (p.x - from.x) * t, y: from.y + (p.y - from.y) * t, rect: p.rect };
        this.#stamp(from);
        left = Math.hypot(p.x - from.x, p.y - from.y);
        travelled = 0;
      }
      d.carry = travelled + left;
      d.last = p;
    }
    this.#redrawSoon();
  }

  #up(e) { if (this.#drag?.id === e.pointerId) this.#drag = null; }

  #stamp(p) {
    const m = this.model;
    if (!m) return;
    if (m.strokes.length >= (this.caps.max_strokes ?? 100000)) { this.note = `stroke limit (${m.strokes.length}) reached`; return; }
    const uv = this.#uv(p);
    if (!uv) return;  // the ray misses the volume
    const s = this.controls.settings;
    m.push({ channel: s.channel, center: [round(uv[0]), round(uv[1])], radius: s.radius, falloff: s.falloff, value: s.value, mode: s.mode, level: s.level });
    this.sync.added();
  }

  // Strokes as the user made them: a drag is one (undo takes it back whole), whatever dabs it
  // painted along its path; dabs from before the first drag (restored from the session) one each.
  #strokeCount(n) {
    const starts = [...new Set(this.#drags.filter((s) => s < n))];
    return (starts.length ? starts[0] : n) + starts.length;
  }

  #redrawSoon() { if (!this.#raf) this.#raf = requestAnimationFrame(() => { this.#raf = 0; this.#redraw(); }); }

  #redraw() {
    const m = this.model, s = this.controls.settings, ui = this.ui;
    ui.previewBox.hidden = !m || !this.caps || !m.strokes.length;  // nothing painted: nothing to preview
    this.preview.draw(m, s.channel);
    const n = m?.strokes.length ?? 0, sync = this.sync, shown = this.#strokeCount(n);
    const count = `${strokes(shown)}${shown !== n ? ` (${n} dabs)` : ''} · ${sync.pending} pending`;
    const status = !m ? 'no ray texture' : [`${m.mapping} ${m.width}×${m.height}`, count,
      sync.queued ? `${sync.queued} queued` : '', sync.failed ? `refused: ${sync.failed}` : '', this.note].filter(Boolean).join(' · ');
    ui.status.textContent = status;
    ui.legend.textContent = `${LEGENDS[s.channel]}\n${count}`;
    ui.section.dataset.strokes = String(n);
    ui.section.dataset.pending = String(sync.pending);
    ui.undo.disabled = !n;
    ui.clear.disabled = !m;
    const tex = m ?? { mapping: s.mapping, width: LONG_SIDE, height: LONG_SIDE };
    const p = this.#pointer, rect = ui.canvas.getBoundingClientRect();
    const uv = p && tex.mapping === 'volume' ? this.#uv({ ...p, rect }, 'volume') : null;
    this.outline.draw(this.painting ? p : null, rect, s, tex, this.scene(), uv);
  }
}
