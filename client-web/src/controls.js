// Render controls built from the capabilities the server's welcome lists, so a method that
// lands on the server later appears here without a client change. Each build (one per welcome)
// owns the listeners of its inputs and releases them when the next build replaces them.
import { Disposer } from './disposer.js';

const LABELS = {
  classification: 'classification', peak_mode: 'peak mode', max_peaks: 'max peaks', sampling: 'sampling',
  s_k: 's_k', step: 'step (world units)', filter: 'filter', virtual_samples: 'virtual samples',
  shading: 'shading', space_skipping: 'space skipping', adaptive: 'adaptive sampling',
};

export class RenderControls extends EventTarget {
  constructor(container, disposer) {
    super();
    this.container = container;
    this.built = new Disposer();
    this.inputs = {};
    disposer.add(() => this.built.dispose());
  }

  build(capabilities, current = {}) {
    this.built.dispose();
    this.container.replaceChildren();
    this.inputs = {};
    const add = (key, input) => {
      const label = document.createElement('label');
      label.append(LABELS[key] ?? key, input);
      this.container.append(label);
      this.inputs[key] = input;
      this.built.listen(input, 'change', () => this.#changed(key));
    };
    for (const key of ['classification', 'peak_mode', 'max_peaks', 'sampling', 'filter', 'virtual_samples']) {
      const options = capabilities[key];
      if (!Array.isArray(options) || options.length === 0) continue;
      const select = document.createElement('select');
      select.name = key;
      for (const o of options) select.append(new Option(String(o), String(o)));
      if (current[key] !== undefined) select.value = String(current[key]);
      add(key, select);
    }
    if ((capabilities.sampling || []).includes('differential')) add('s_k', this.#number('s_k', current.s_k ?? 4));
    add('step', this.#number('step', current.step ?? ''));
    for (const key of ['shading', 'space_skipping', 'adaptive']) {
      if (capabilities[key] !== true) continue;
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.name = key;
      box.checked = current[key] ?? key === 'space_skipping';
      add(key, box);
    }
  }

  #number(name, value) {
    const n = document.createElement('input');
    n.type = 'number';
    n.step = 'any';
    n.min = '0';
    n.name = name;
    n.placeholder = 'default';
    n.value = value;
    return n;
  }

  #changed(key) {
    const input = this.inputs[key];
    let value;
    if (input.type === 'checkbox') value = input.checked;
    else if (input.type === 'number') value = input.value === '' ? null : parseFloat(input.value);
    else value = /^\d+$/.test(input.value) && key !== 'classification' ? parseInt(input.value, 10) : input.value;
    this.dispatchEvent(new CustomEvent('change', { detail: { [key]: value } }));  // null removes the key (merge patch)
  }
}
