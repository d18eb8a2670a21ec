// Render controls built from the capabilities the server's welcome lists, so a method that
// lands on the server later appears here without a client change. Each build (one per welcome)
// owns the listeners of its inputs and releases them when the next build replaces them. Every
// control says what it does (its tooltip); a control that does not apply to the current
// settings is disabled (peak mode without peak finding, s_k without differential sampling); a
// number outside its limits is marked and not sent.
import { Disposer } from './disposer.js';

const LABELS = {
  classification: 'classification', peak_mode: 'peak mode', max_peaks: 'max peaks', sampling: 'sampling',
  s_k: 's_k', step: 'step', filter: 'filter', virtual_samples: 'virtual samples',
  shading: 'shading', space_skipping: 'space skipping', adaptive: 'adaptive sampling',
};
// What each control does (docs/scenes.md has the whole story).
export const HELP = {
  classification: 'post: the TF applied to each sample (DVR). preint: a preintegrated table per segment, smoother at ' +
    'large steps. peaks: DVR plus the TF\'s opacity peaks found between samples and drawn as crisp surfaces (Knoll 2009). ' +
    'mip, minip, average: intensity projections, the largest, smallest or mean value along each ray, coloured by ' +
    'the TF at that value (sparse structure such as axons or vessels reads at once in a MIP).',
  peak_mode: 'With peak finding: dvr+peaks draws both; xor draws a segment\'s peak instead of its DVR; peaks_only ' +
    'the surfaces alone; dvr_only leaves peak finding out.',
  max_peaks: 'With peak finding: how many peak crossings one segment between samples may hold (1 to 4).',
  sampling: 'uniform: one step along every ray. differential: the step grows with distance from the eye ' +
    '(Knoll §5), scaled by s_k; perspective cameras only.',
  s_k: 'With differential sampling: the step where a ray crosses the focal plane in units of the pixel footprint ' +
    'there; smaller is finer and slower.',
  step: 'The sample step in the volume\'s unit (empty: the smallest voxel spacing). At least 1/1000 of that spacing.',
  filter: 'trilinear: hardware-style interpolation. tricubic: a smooth B-spline from 8 trilinear fetches, slower, ' +
    'fewer staircase artefacts.',
  virtual_samples: 'Catmull-Rom samples between the true ones (Lee 2010): 3 or 7 per segment, smoother at large steps.',
  shading: 'Blinn-Phong lighting with a head light, from the field\'s gradient.',
  space_skipping: 'Skip the macrocells the TF leaves empty. Changes no pixel, saves time.',
  adaptive: 'A step per macrocell from its spread of values (Knoll §6.2): finer where the data varies.',
};

// The classifications that are intensity projections (one value per ray: no shading, no TF skipping).
const PROJECTIONS = new Set(['mip', 'minip', 'average']);

export class RenderControls extends EventTarget {
  constructor(container, disposer) {
    super();
    this.container = container;
    this.built = new Disposer();
    this.inputs = {};
    this.minStep = 0;  // from the volume: 1/1000 of its smallest spacing
    this.unit = 'units';  // the volume's unit of length (units.js), shown with the step
    disposer.add(() => this.built.dispose());
  }

  build(capabilities, current = {}) {
    this.built.dispose();
    this.container.replaceChildren();
    this.inputs = {};
    const add = (key, input) => {
      const label = document.createElement('label');
      label.title = HELP[key] ?? '';
      input.title = label.title;
      // The whole story of each setting: docs/scenes.md, served by the server beside the client.
      const doc = Object.assign(document.createElement('a'), { href: '/docs/scenes.md#render', target: '_blank',
        rel: 'noopener', className: 'doc', textContent: '?', title: `${LABELS[key] ?? key} in docs/scenes.md` });
      doc.setAttribute('aria-label', `${LABELS[key] ?? key}: explained in docs/scenes.md`);
      const name = document.createElement('span');
      const text = document.createTextNode(key === 'step' ? `step (${this.unit})` : LABELS[key] ?? key);
      if (key === 'step') this.stepText = text;
      name.append(text, ' ', doc);
      label.append(name, input);
      this.container.append(label);
      this.inputs[key] = input;
      this.built.listen(input, input.type === 'number' ? 'input' : 'change', () => this.#changed(key));
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
    this.#applicable();
  }

  setVolume(info) { this.minStep = 1e-3 * Math.min(...info.spacing); }

  setUnit(unit) {
    this.unit = unit;
    if (this.stepText) this.stepText.data = `step (${unit})`;
  }

  // Sets controls as the user would (a preset that needs peak finding and shading), sending one
  // change with every key.
  set(values) {
    const patch = {};
    for (const [key, value] of Object.entries(values)) {
      const input = this.inputs[key];
      if (!input) continue;
      if (input.type === 'checkbox') input.checked = !!value;
      else input.value = String(value);
      patch[key] = value;
    }
    this.#applicable();
    if (Object.keys(patch).length) this.dispatchEvent(new CustomEvent('change', { detail: patch }));
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

  // Disabled where it does not apply, with the reason in its tooltip.
  #applicable() {
    const v = (k) => this.inputs[k]?.value;
    const rules = {
      peak_mode: [v('classification') === 'peaks', 'applies with classification peaks'],
      max_peaks: [v('classification') === 'peaks' && v('peak_mode') !== 'dvr_only', 'applies with peak finding'],
      s_k: [v('sampling') === 'differential', 'applies with differential sampling'],
      shading: [!PROJECTIONS.has(v('classification')), 'a projection is not shaded'],
      space_skipping: [!PROJECTIONS.has(v('classification')),
        'a projection does not skip by the TF (mip and minip skip the cells that cannot change them)'],
    };
    for (const [key, [on, why]] of Object.entries(rules)) {
      const input = this.inputs[key];
      if (!input) continue;
      input.disabled = !on;
      input.title = on ? HELP[key] : `${HELP[key]} (${why})`;
    }
  }

  // A number outside its limits: marked, explained, not sent (the last valid value stays).
  #invalid(key, value) {
    if (value === null) return '';
    if (!Number.isFinite(value)) return 'a number';
    if (key === 's_k' && !(value > 0)) return 'must be > 0';
    if (key === 'step' && !(value > 0 && value >= this.minStep))
      return `must be at least ${+this.minStep.toPrecision(3)} (1/1000 of the smallest spacing)`;
    return '';
  }

  #changed(key) {
    const input = this.inputs[key];
    let value;
    if (input.type === 'checkbox') value = input.checked;
    else if (input.type === 'number') value = input.value === '' ? null : parseFloat(input.value);
    else value = /^\d+$/.test(input.value) && key !== 'classification' ? parseInt(input.value, 10) : input.value;
    if (input.type === 'number') {
      const why = this.#invalid(key, value);
      input.setAttribute('aria-invalid', String(!!why));
      input.classList.toggle('invalid', !!why);
      input.title = why ? `${LABELS[key]} ${why}` : HELP[key];
      if (why) return;
    }
    this.#applicable();
    this.dispatchEvent(new CustomEvent('change', { detail: { [key]: value } }));  // null removes the key (merge patch)
  }
}
