// The brush's controls, built from the welcome's capabilities.ray_texture like the render
// controls: drag mode (orbit / paint), mapping, channel, mode, value, radius, fall-off, level.
// The settings outlive the rebuilds (one per welcome); each build owns its listeners.
import { Disposer } from './disposer.js';
import { valueRange } from './ray-texture-model.js';

// A sensible first value for each mode and channel (within the ranges valueRange gives).
const DEFAULT_VALUE = {
  set: { step: 0.25, termination: 0, blend: 1 },
  add: { step: 1, termination: -0.25, blend: 0.5 },
  multiply: { step: 0.5, termination: 0.5, blend: 0.5 },
};

export class BrushControls extends EventTarget {
  settings = { drag: 'orbit', mapping: 'view', channel: 'termination', mode: 'set', value: 0, radius: 0.05, falloff: 0.3, level: 0 };
  inputs = {};

  constructor(container, disposer) {
    super();
    this.container = container;
    this.built = new Disposer();
    disposer.add(() => this.built.dispose());
  }

  build(caps) {
    this.built.dispose();
    this.container.replaceChildren();
    this.inputs = {};
    this.caps = caps;
    const s = this.settings;
    if (!caps.mappings.includes(s.mapping)) s.mapping = caps.mappings[0];
    if (!caps.channels[s.channel]) s.channel = Object.keys(caps.channels)[0];
    if (!caps.modes.includes(s.mode)) s.mode = caps.modes[0];
    s.level = Math.min(s.level, caps.max_level ?? 8);

    const drag = document.createElement('fieldset');
    drag.className = 'row';
    drag.append(Object.assign(document.createElement('legend'), { textContent: 'drag' }));
    for (const [value, text] of [['orbit', 'orbit'], ['paint', 'paint ray texture']]) {
      const radio = Object.assign(document.createElement('input'), { type: 'radio', name: 'brush-drag', value, checked: s.drag === value });
      const label = document.createElement('label');
      label.append(radio, ' ' + text);
      drag.append(label);
      this.inputs[`drag-${value}`] = radio;
      this.built.listen(radio, 'change', () => radio.checked && this.#set('drag', value));
    }
    this.container.append(drag);

    this.#select('mapping', 'mapping', caps.mappings, 'switching the mapping clears the strokes: a stroke means another place in the other mapping');
    this.#select('channel', 'channel', Object.keys(caps.channels));
    this.#select('mode', 'mode', caps.modes);
    const value = this.#input('value', 'value', { type: 'number', step: 'any' });
    value.title = 'set: the channel value; add: added; multiply: the factor';
    this.#input('radius', 'radius', { type: 'range', min: 0.005, max: 0.5, step: 0.005 }, (x) => x.toFixed(3));
    this.#input('falloff', 'fall-off', { type: 'range', min: 0, max: 1, step: 0.05 }, (x) => x.toFixed(2));
    this.#input('level', 'level (2^L blocks)', { type: 'number', min: 0, max: caps.max_level ?? 8, step: 1 });
    this.#limitValue(false);
  }

  // The value's bounds follow the channel and the mode.
  #limitValue(reset) {
    const s = this.settings, input = this.inputs.value;
    const [lo, hi] = valueRange(s.channel, s.mode, this.caps.channels);
    if (reset || !(s.value >= lo && s.value <= hi)) s.value = Math.min(hi, Math.max(lo, DEFAULT_VALUE[s.mode]?.[s.channel] ?? lo));
    input.min = String(lo);
    input.max = String(hi);
    input.value = String(s.value);
  }

  #select(key, text, options, title) {
    const select = document.createElement('select');
    select.name = `brush-${key}`;
    for (const o of options) select.append(new Option(o, o));
    select.value = this.settings[key];
    if (title) select.title = title;
    return this.#add(key, text, select, () => select.value);
  }

  #input(key, text, attrs, show) {
    const input = document.createElement('input');
    input.name = `brush-${key}`;
    for (const [k, v] of Object.entries(attrs)) input.setAttribute(k, String(v));
    input.value = String(this.settings[key]);
    const out = show ? Object.assign(document.createElement('output'), { textContent: show(this.settings[key]) }) : null;
    this.#add(key, text, input, () => {
      const lo = +input.min, hi = +input.max, x = parseFloat(input.value);
      const v = Number.isFinite(x) ? Math.min(hi, Math.max(lo, key === 'level' ? Math.round(x) : x)) : this.settings[key];
      if (key === 'radius' && !(v > 0)) return this.settings.radius;
      if (String(v) !== input.value) input.value = String(v);
      if (out) out.textContent = show(v);
      return v;
    }, out);
    return input;
  }

  #add(key, text, input, read, out) {
    const label = document.createElement('label');
    if (out) {
      const pair = Object.assign(document.createElement('span'), { className: 'pair' });
      pair.append(input, out);
      label.append(text, pair);
    } else label.append(text, input);
    this.container.append(label);
    this.inputs[key] = input;
    this.built.listen(input, input.type === 'range' ? 'input' : 'change', () => this.#set(key, read()));
    return input;
  }

  #set(key, value) {
    this.settings[key] = value;
    if (key === 'channel' || key === 'mode') this.#limitValue(true);
    this.dispatchEvent(new CustomEvent('change', { detail: { key, value } }));
  }

  setDrag(mode) {
    this.settings.drag = mode;
    if (this.inputs[`drag-${mode}`]) this.inputs[`drag-${mode}`].checked = true;
  }
}
