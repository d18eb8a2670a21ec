// A time series' controls (docs/scenes.md, "Time"): a slider over the volume's time points, a
// readout, and play/pause at a chosen rate. The server is asked for one time point at a time: a
// step waits until a frame of the time point asked for has arrived, and playing moves on by the
// clock, so a server that cannot keep up skips time points instead of queueing them, and frames
// arrive in order. Shown only for a volume with more than one time point.
export class TimeControls extends EventTarget {
  time = 0;       // the time point shown (the last frame's)
  times = 1;      // how many the volume has
  #asked = null;  // the time point sent and not yet drawn
  #want = null;   // the one to send once it is
  #timer = 0;
  #clock = null;  // playing: { start (ms), from (time point) }

  constructor(ui, disposer) {
    super();
    this.ui = ui;
    disposer.listen(ui.slider, 'input', () => { this.pause(); this.step(+ui.slider.value); });
    disposer.listen(ui.play, 'click', () => (this.#clock ? this.pause() : this.play()));
    disposer.listen(ui.rate, 'change', () => { if (this.#clock) this.play(); });
    disposer.add(() => clearInterval(this.#timer));
  }

  get playing() { return !!this.#clock; }

  // A volume (its info's `times`) and the time point the state carries.
  setVolume(info, time = 0) {
    this.pause();
    this.times = Math.max(1, info.times ?? 1);
    this.time = Math.min(time, this.times - 1);
    this.#asked = this.#want = null;
    this.ui.root.hidden = this.times < 2;
    this.ui.slider.max = String(this.times - 1);
    this.#show();
  }

  // A frame arrived, drawn at time point `t` (its stats' `time`).
  drawn(t) {
    if (t === undefined) return;
    this.time = t;
    if (this.#asked === t) this.#asked = null;
    this.#show();
    if (this.#asked === null && this.#want !== null && this.#want !== t) this.#send(this.#want);
  }

  // The server refused the time point asked for (said by the error line): ask again freely.
  failed() { this.#asked = this.#want = null; this.#show(); }

  // Asks for time point t (clamped); waits for the frame of one already asked for.
  step(t) {
    t = Math.max(0, Math.min(this.times - 1, Math.round(t)));
    this.#want = t;
    if (this.#asked === null && t !== this.time) this.#send(t);
    this.#show(t);
  }

  play() {
    clearInterval(this.#timer);
    const rate = Math.max(0.1, Math.min(60, +this.ui.rate.value || 5));
    this.#clock = { start: performance.now(), from: this.time, rate };
    this.#timer = setInterval(() => {
      const c = this.#clock, n = Math.floor(((performance.now() - c.start) / 1000) * c.rate);
      this.step((c.from + n) % this.times);
    }, Math.max(15, 250 / rate));
    this.ui.play.textContent = '⏸';
    this.ui.play.setAttribute('aria-pressed', 'true');
  }

  pause() {
    clearInterval(this.#timer);
    this.#timer = 0;
    this.#clock = null;
    this.ui.play.textContent = '▶';
    this.ui.play.setAttribute('aria-pressed', 'false');
  }

  #send(t) {
    this.#asked = t;
    this.dispatchEvent(new CustomEvent('time', { detail: t }));
  }

  #show(target = this.#want ?? this.time) {
    if (!this.#clock) this.ui.slider.value = String(target);
    else this.ui.slider.value = String(this.time);
    this.ui.readout.textContent = `t ${this.time} of 0…${this.times - 1}`;
  }
}
