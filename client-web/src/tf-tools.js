// The TF editor's tools: window/level (the TF spread over another range of values), the
// histogram's axis (log or linear), and the TF saved to and loaded from JSON (the scene's tf:
// {"points": [[value, r, g, b, a], ...]}; a whole scene file loads its tf).
import { windowLevel } from './tf-model.js';

export function bindTfTools(editor, ui, disposer) {
  // A window/level that cannot apply is marked on its field and said, and changes nothing (so undo
  // still undoes the last edit that did).
  const mark = (input, why) => {
    input.setAttribute('aria-invalid', String(!!why));
    input.classList.toggle('invalid', !!why);
    input.title = why;
  };
  const show = () => {
    const p = editor.points;
    if (!p.length) return;
    const a = p[0][0], b = p[p.length - 1][0];
    // Unfocused fields show the TF's own window and level (a refused entry gives way to them).
    if (document.activeElement !== ui.window) ui.window.value = +(b - a).toPrecision(5), mark(ui.window, '');
    if (document.activeElement !== ui.level) ui.level.value = +((a + b) / 2).toPrecision(5), mark(ui.level, '');
  };
  disposer.listen(editor, 'change', show);
  disposer.listen(editor, 'drawn', show);
  const wl = () => {
    const w = parseFloat(ui.window.value), l = parseFloat(ui.level.value);
    if (editor.points.length < 2) return;
    const { lo, hi } = editor, fmt = (v) => +v.toPrecision(5);
    const badWindow = !(w > 0) ? 'the window must be a number > 0' : '';
    const badLevel = !Number.isFinite(l) ? 'the level must be a number'
      : !badWindow && (l + w / 2 < lo || l - w / 2 > hi)
        ? `the window ${fmt(l - w / 2)}…${fmt(l + w / 2)} misses the data's range ${fmt(lo)}…${fmt(hi)}` : '';
    mark(ui.window, badWindow);
    mark(ui.level, badLevel);
    if (badWindow || badLevel) {
      ui.note.textContent = `⚠ ${badWindow || badLevel}`;
      return;
    }
    const next = windowLevel(editor.points, w, l);
    if (JSON.stringify(next) !== JSON.stringify(editor.points)) editor.apply(next);  // no empty undo steps
  };
  disposer.listen(ui.window, 'change', wl);
  disposer.listen(ui.level, 'change', wl);
  disposer.listen(ui.log, 'change', () => { editor.logHistogram = ui.log.checked; editor.draw(); });
  disposer.listen(ui.save, 'click', () => {
    const blob = new Blob([JSON.stringify({ points: editor.points }, null, 1)], { type: 'application/json' });
    const url = URL.createObjectURL(blob);
    Object.assign(document.createElement('a'), { href: url, download: 'tf.json' }).click();
    setTimeout(() => URL.revokeObjectURL(url), 1000);
  });
  disposer.listen(ui.load, 'change', async () => {
    const file = ui.load.files?.[0];
    ui.load.value = '';
    if (!file) return;
    try {
      editor.apply(parseTf(await file.text()));
      ui.note.textContent = `TF loaded from ${file.name}`;
    } catch (e) {
      ui.note.textContent = `⚠ ${file.name}: ${e.message}`;
    }
  });
}

// {"points": [...]}, {"tf": {"points": [...]}} (a scene) or a bare list of points; checked as
// the server checks a scene's tf.
export function parseTf(text) {
  const j = JSON.parse(text);
  const points = Array.isArray(j) ? j : j?.points ?? j?.tf?.points;
  if (!Array.isArray(points) || points.length < 1 || points.length > 1024) throw new Error('no TF points (1 to 1024 of them)');
  for (const p of points)
    if (!Array.isArray(p) || p.length !== 5 || !p.every(Number.isFinite) || p.slice(1).some((x) => x < 0 || x > 1))
      throw new Error('each point is [value, r, g, b, a] with r, g, b, a in 0..1');
  for (let i = 1; i < points.length; i++)
    if (points[i][0] < points[i - 1][0]) throw new Error('points must be sorted by value');
  return points;
}
