// The stats overlay: frames per second, input -> frame-displayed latency, bytes per frame,
// samples per ray, interactive/final, and the shader variant.
export class StatsOverlay {
  #shown = [];        // display times in the last second
  #latency = { interactive: [], final: [] };
  #inputSent = new Map();  // camera version -> time the input was sent
  last = {};

  constructor(element) { this.el = element; }

  inputSent(cameraVersion) {
    this.#inputSent.set(cameraVersion, performance.now());
    if (this.#inputSent.size > 512) this.#inputSent.delete(this.#inputSent.keys().next().value);
  }

  frameShown(frame) {
    const now = performance.now();
    this.#shown.push(now);
    while (this.#shown.length && now - this.#shown[0] > 1000) this.#shown.shift();
    const sent = this.#inputSent.get(frame.cameraVersion);
    if (sent !== undefined) {
      const list = this.#latency[frame.final ? 'final' : 'interactive'];
      list.push(now - sent);
      if (list.length > 200) list.shift();
      if (frame.final) this.#inputSent.delete(frame.cameraVersion);
    }
    this.last.frame = frame;
    this.render();
  }

  stats(msg) { this.last.stats = msg; this.render(); }

  percentile(kind, p) {
    const v = [...this.#latency[kind]].sort((a, b) => a - b);
    return v.length ? v[Math.min(v.length - 1, Math.round(p * (v.length - 1)))] : NaN;
  }
  latencies(kind) { return [...this.#latency[kind]]; }

  render() {
    const f = this.last.frame, s = this.last.stats ?? {};
    if (!f) return;
    const ms = (x) => (Number.isFinite(x) ? x.toFixed(0) + ' ms' : '–');
    this.el.textContent = [
      `${f.final ? 'final' : 'interactive'} ${f.width}×${f.height}  ${this.#shown.length} fps`,
      `input→frame p50 ${ms(this.percentile('interactive', 0.5))} / final ${ms(this.percentile('final', 0.5))}`,
      `${((s.bytes ?? f.image.byteLength) / 1024).toFixed(1)} KiB/frame  q${f.quality}`,
      `render ${ms(s.render_ms)}  encode ${ms(s.encode_ms)}`,
      `samples/ray ${s.samples_per_ray?.toFixed(1) ?? '–'}`,
    ].join('\n');
  }
}
