// The keyboard and the layout around the view: the 3D view takes keys when focused (arrows
// orbit, Shift+arrows pan, + and - zoom, R resets, S shows or hides the stats, M measures (Esc
// ends it), F fullscreen, ? the help); the
// help overlay lists them; the side panel collapses (a button, or the narrow layout's default).
const ORBIT_PX = 24, PAN_PX = 24, ZOOM = 0.9;

export function bindViewKeys({ canvas, camera, help, toggleStats, measure, measuring, fullscreen }, disposer) {
  disposer.listen(canvas, 'keydown', (e) => {
    const k = e.key;
    if (k.startsWith('Arrow')) {
      const dx = k === 'ArrowLeft' ? -1 : k === 'ArrowRight' ? 1 : 0, dy = k === 'ArrowUp' ? -1 : k === 'ArrowDown' ? 1 : 0;
      if (e.shiftKey) camera.pan(dx * PAN_PX, dy * PAN_PX);
      else camera.orbit(dx * ORBIT_PX, dy * ORBIT_PX);
    } else if (k === '+' || k === '=') camera.zoom(ZOOM);
    else if (k === '-' || k === '_') camera.zoom(1 / ZOOM);
    else if (k === 'r' || k === 'R') camera.reset();
    else if (k === 's' || k === 'S') toggleStats();
    else if (k === '?') toggle(help);
    else if (k === 'm' || k === 'M') measure();
    else if (k === 'f' || k === 'F') fullscreen();
    else if (k === 'Escape' && !help.hidden) help.hidden = true;
    else if (k === 'Escape' && measuring()) measure();
    else return;
    e.preventDefault();
  });
}

export function toggle(el, show = el.hidden) {
  el.hidden = !show;
  return show;
}

// The panel: collapsed by its button; collapsed at first where the window is narrow, so the
// view keeps its width (a tablet, a half-screen window).
export function bindPanel({ panel, button }, disposer) {
  const narrow = window.matchMedia('(max-width: 900px)');
  const set = (open) => {
    document.body.classList.toggle('panel-collapsed', !open);
    button.setAttribute('aria-expanded', String(open));
    button.textContent = open ? '⟩' : '⟨ settings';
    button.title = open ? 'hide the settings panel' : 'show the settings panel';
    window.dispatchEvent(new Event('resize'));  // the view's size changed: a new viewport
  };
  set(!narrow.matches);
  disposer.listen(button, 'click', () => set(document.body.classList.contains('panel-collapsed')));
  return { open: () => set(true), close: () => set(false), get isOpen() { return !document.body.classList.contains('panel-collapsed'); }, panel };
}

// The whole page fullscreen (the panel stays reachable; collapse it for the view alone).
export function toggleFullscreen() {
  if (document.fullscreenElement) return document.exitFullscreen();
  return document.documentElement.requestFullscreen().catch(() => {});
}
