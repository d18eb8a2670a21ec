// Lengths with their unit (docs/scenes.md, "Units"). The volume's unit comes from its file (the
// server's volume info: "µm", "nm", "mm", ...) or the scene's `units`; "units" when neither names
// one. Distances and the scale bar move to the SI prefix that keeps the number between 1 and 1000
// (2500 µm reads 2.5 mm), as Neuroglancer's scale bar does; positions stay in the volume's unit.
const SI = [['pm', 1e-12], ['nm', 1e-9], ['µm', 1e-6], ['mm', 1e-3], ['m', 1], ['km', 1e3]];
const METRES = new Map([...SI, ['Å', 1e-10], ['cm', 1e-2]]);

// The unit a viewer shows lengths in: the scene's, else the volume's, else "units".
export function lengthUnit(volume, state) { return state?.units || volume?.units || 'units'; }

// `v` (in `unit`) as the display unit's number and symbol.
function display(v, unit) {
  const m = METRES.get(unit);
  if (!m || !(Math.abs(v) > 0) || !Number.isFinite(v)) return [v, unit];
  const metres = Math.abs(v) * m;
  let pick = SI[0];
  for (const s of SI) if (metres >= s[1] * (1 - 1e-9)) pick = s;
  return [(v * m) / pick[1], pick[0]];
}

// A length as text: "2.5 mm", "120 units".
export function formatLength(v, unit, digits = 4) {
  const [x, u] = display(v, unit);
  return `${+x.toPrecision(digits)} ${u}`;
}

// The scale bar: the largest 1, 2 or 5 × 10^k of the display unit not over `target` (in
// `unit`); its length in `unit` and its label.
export function niceLength(target, unit) {
  const [t, u] = display(target, unit);
  const p10 = 10 ** Math.floor(Math.log10(t));
  const nice = [1, 2, 5, 10].map((k) => k * p10).filter((x) => x <= t * (1 + 1e-9)).pop() ?? p10;
  return { length: (nice / t) * target, label: `${+nice.toPrecision(3)} ${u}` };
}
