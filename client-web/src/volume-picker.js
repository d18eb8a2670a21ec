// Volume picker: the server's loaded volumes, or a path inside a data directory; shows progress
// until the server answers with the new volume.
export class VolumePicker extends EventTarget {
  constructor(ui, disposer) {
    super();
    this.ui = ui;
    disposer.listen(ui.select, 'change', () => this.#pick(ui.select.value));
    disposer.listen(ui.open, 'click', () => ui.path.value && this.#pick(ui.path.value.trim()));
    disposer.listen(ui.path, 'keydown', (e) => { if (e.key === 'Enter' && ui.path.value.trim()) this.#pick(ui.path.value.trim()); });
  }

  show(volumes, current) {
    const label = (v) => `${v.uploaded ? `${v.name} (uploaded, ` : `${v.id} (`}${v.dims.join('×')} ${v.dtype})`;
    this.ui.select.replaceChildren(...volumes.map((v) => new Option(label(v), v.id)));
    this.ui.select.value = current.id;
    this.ui.info.textContent = `${current.dims.join('×')} ${current.dtype}, spacing ${current.spacing.join(' ')}, range ${current.range.map((x) => +x.toPrecision(5)).join(' … ')}`;
    this.ui.progress.textContent = '';
  }

  failed(message) { this.ui.progress.textContent = '⚠ ' + message; }

  #pick(id) {
    this.ui.progress.textContent = 'loading…';
    this.dispatchEvent(new CustomEvent('pick', { detail: id }));
  }
}
