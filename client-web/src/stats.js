// The stats overlay: frames per second, input -> frame-displayed latency, bytes per frame,
// samples per ray, interactive/final, and the shader variant.
export class StatsOverlay {
  #shown = [];        // display times in the last second
  #latency = { interactive: [], final: [] };
  #parts = { interactive: [], final: [] };
  #renderMs = { interactive: [], final: [] };  // the server's render ms per frame (stats messages)  // per frame: where the input -> frame time went
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
      const kind = frame.final ? 'final' : 'interactive';
      const list = this.#latency[kind];
      list.push(now - sent);
      if (list.length > 200) list.shift();
      // Where that time went: the server's clock from the input's arrival to the render's end
      // and the encode's, the page's from receipt to decoded and to drawn; the rest is the way
      // there and back (and the page's own queues).
      const parts = this.#parts[kind];
      parts.push({ total: now - sent, server_render: (frame.tRenderUs - frame.tInputUs) / 1000,
        encode: (frame.tEncodeUs - frame.tRenderUs) / 1000, decode: frame.decodedAt - frame.receivedAt,
        draw: now - frame.decodedAt, width: frame.width, height: frame.height });
      if (parts.length > 200) parts.shift();
      if (frame.final) this.#inputSent.delete(frame.cameraVersion);
    }
    this.last.frame = frame;
    this.render();
  }

  stats(msg) {
    this.last.stats = msg;
    this.#renderMs[msg.final ? 'final' : 'interactive'].push(msg.render_ms);
    for (const k of ['final', 'interactive']) if (this.#renderMs[k].length > 200) this.#renderMs[k].shift();
    this.render();
  }
  renderTimes(kind) { return [...this.#renderMs[kind]]; }

  percentile(kind, p) {
    const v = [...this.#latency[kind]].sort((a, b) => a - b);
    return v.length ? v[Math.min(v.length - 1, Math.round(p * (v.length - 1)))] : NaN;
  }
  latencies(kind) { return [...this.#latency[kind]]; }
  latencyParts(kind) { return this.#parts[kind].map((p) => ({ ...p })); }

  render() {
    const f = this.last.frame, s = this.last.stats ?? {};
    if (!f) return;
    const ms = (x) => (Number.isFinite(x) ? x.toFixed(0) + ' ms' : '–');
    this.el.textContent = [
      `${f.final ? 'final' : 'interactive'} ${f.width}×${f.height}  ${this.#shown.length} fps`,
      `input→frame p50 ${ms(this.percentile('interactive', 0.5))} / final ${ms(this.percentile('final', 0.5))}`,
      `${s.codec ?? 'jpeg'}  ${((s.bytes ?? f.image.byteLength) / 1024).toFixed(1)} KiB/frame  ` +
        (Number.isFinite(s.kbps) ? `${s.kbps.toFixed(0)} kbit/s` : `q${f.quality}`),
      `render ${ms(s.render_ms)}  encode ${ms(s.encode_ms)}  decode ${ms(f.decodeMs ?? (f.decodedAt - f.receivedAt))}`,
      `samples/ray ${s.samples_per_ray?.toFixed(1) ?? '–'}`,
    ].join('\n');
  }
}
