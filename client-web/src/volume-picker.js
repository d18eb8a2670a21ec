// Volume picker: the server's loaded volumes, or a path inside a data directory (typed, or chosen
// in the data browser); shows what is loading and for how long until the server answers with the
// new volume, with the share of the file read so far when the server tells it (loading messages).
export class VolumePicker extends EventTarget {
  #timer = 0;
  #tick = null;
  #fraction = null;

  constructor(ui, disposer) {
    super();
    this.ui = ui;
    disposer.add(() => clearInterval(this.#timer));
    disposer.listen(ui.select, 'change', () => this.#pick(ui.select.value));
    disposer.listen(ui.open, 'click', () => ui.path.value && this.#pick(ui.path.value.trim()));
    disposer.listen(ui.path, 'keydown', (e) => { if (e.key === 'Enter' && ui.path.value.trim()) this.#pick(ui.path.value.trim()); });
  }

  show(volumes, current) {
    const label = (v) => `${v.uploaded ? `${v.name} (uploaded, ` : `${v.id} (`}${v.dims.join('×')} ${v.dtype})`;
    this.ui.select.replaceChildren(...volumes.map((v) => new Option(label(v), v.id)));
    this.ui.select.value = current.id;
    this.ui.info.textContent = `${current.dims.join('×')} ${current.dtype}, spacing ${current.spacing.map((x) => +x.toPrecision(5)).join(' ')} ${current.units ?? 'units'}, range ${current.range.map((x) => +x.toPrecision(5)).join(' … ')}`;
    this.#done('');
  }

  failed(message) { this.#done('⚠ ' + message); }

  // A loading message: how much of `volume` the server has read. Also for the volume a first
  // hello asked for, which no pick started.
  loading({ volume, fraction }) {
    if (!this.#timer) this.#start(volume);
    this.#fraction = fraction;
    this.#tick();
  }

  // Opens a volume by id or data-directory path; `bytes`, when known, is shown while it loads.
  pick(id, bytes = 0) { this.#pick(id, bytes); }

  #done(text) {
    clearInterval(this.#timer);
    this.#timer = 0;
    this.#fraction = null;
    this.ui.progress.textContent = text;
  }

  #start(id, bytes = 0) {
    const start = performance.now(), size = bytes ? ` (${formatBytes(bytes)})` : '';
    this.#fraction = null;
    this.#tick = () => {
      const s = Math.round((performance.now() - start) / 1000);
      const f = this.#fraction;
      const read = f === null ? '' : f < 1 ? ` ${Math.floor(f * 100)}%` : ' read, preparing';
      this.ui.progress.textContent = `loading ${id}${size}…${read}${s >= 1 ? ` ${s} s` : ''}`;
    };
    clearInterval(this.#timer);
    this.#tick();
    this.#timer = setInterval(this.#tick, 1000);
  }

  #pick(id, bytes = 0) {
    this.#start(id, bytes);
    this.dispatchEvent(new CustomEvent('pick', { detail: id }));
  }
}

export function formatBytes(n) {
  const units = ['B', 'KiB', 'MiB', 'GiB', 'TiB'];
  let i = 0;
  while (n >= 1024 && i < units.length - 1) { n /= 1024; i++; }
  return `${+n.toPrecision(3)} ${units[i]}`;
}
