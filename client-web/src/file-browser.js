// The data-directory browser (GET /api/files, docs/rest.md): the folders of the server's data
// directories one at a time, by relative names; a volume (or a folder that opens as one) is
// picked with a click, a folder is looked into.
import { formatBytes } from './volume-picker.js';

export class FileBrowser extends EventTarget {
  dir = '';

  constructor({ button, list }, { token }, disposer) {
    super();
    Object.assign(this, { button, list, token });
    disposer.listen(button, 'click', () => (list.hidden ? this.open(this.dir) : this.close()));
  }

  close() {
    this.list.hidden = true;
    this.button.setAttribute('aria-expanded', 'false');
  }

  async open(dir) {
    const headers = this.token() ? { Authorization: `Bearer ${this.token()}` } : {};
    let answer;
    try {
      const res = await fetch(`/api/files?dir=${encodeURIComponent(dir)}`, { headers });
      answer = await res.json();
      if (!res.ok) throw new Error(answer.message);
    } catch (e) {
      this.#render(dir, [], `⚠ ${e.message}`);
      return;
    }
    this.dir = answer.dir;
    this.#render(answer.dir, answer.entries, answer.truncated ? 'only the first entries are listed' : '');
  }

  #render(dir, entries, note) {
    const items = [];
    const button = (text, title, fn) => {
      const b = Object.assign(document.createElement('button'), { type: 'button', textContent: text, title });
      b.addEventListener('click', fn);
      const li = document.createElement('li');
      li.append(b);
      return li;
    };
    const heading = Object.assign(document.createElement('li'), { className: 'muted', textContent: `data/${dir}` });
    items.push(heading);
    if (dir) {
      const up = dir.split('/').slice(0, -1).join('/');
      items.push(button('↑ ..', 'the folder above', () => this.open(up)));
    }
    for (const e of entries) {
      if (e.kind === 'folder') items.push(button(`📁 ${e.name}/`, `look into ${e.path}`, () => this.open(e.path)));
      else {
        // A DICOM series: its modality, size and description (never a patient's name: the server sends none).
        const what = e.format === 'dicom' ? `a DICOM ${e.modality || ''} series, ${e.dims.join('×')}`
          : e.kind === 'stack' ? 'a folder that opens as one volume' : formatBytes(e.bytes);
        const label = e.format === 'dicom' && e.description && !e.name.endsWith(e.description) ? `${e.name} — ${e.description}` : e.name;
        items.push(button(`${e.kind === 'stack' ? '🗂' : '▦'} ${label}`, `open ${e.path} (${what})`, () => {
          this.close();
          this.dispatchEvent(new CustomEvent('pick', { detail: { path: e.path, bytes: e.bytes } }));
        }));
      }
    }
    if (!entries.length && !note) note = 'nothing to open here';
    if (note) items.push(Object.assign(document.createElement('li'), { className: 'muted', textContent: note }));
    this.list.replaceChildren(...items);
    this.list.hidden = false;
    this.button.setAttribute('aria-expanded', 'true');
  }
}
