// peakcast browser client: wires the stream, the viewport, the camera, the TF editor, the render
// controls, the ray-texture brush, the stats overlay, the volume picker, screenshots and the
// shareable URL.
import { Brush } from './brush.js';
import { CameraController } from './camera.js';
import { RenderControls } from './controls.js';
import { Disposer } from './disposer.js';
import { readState, stateUrl, takeTokenFromUrl, writeState } from './state-url.js';
import { StatsOverlay } from './stats.js';
import { CodecPicker } from './codec-picker.js';
import { Stream } from './stream.js';
import { TfEditor } from './tf-editor.js';
import { VolumePicker } from './volume-picker.js';
import { FileBrowser } from './file-browser.js';
import { DropUpload } from './upload.js';
import { bindPanel, bindViewKeys, toggle, toggleFullscreen } from './keys.js';
import { Probe } from './probe.js';
import { lengthUnit } from './units.js';
import { TimeControls } from './time-controls.js';
import { ClipControls } from './clip-controls.js';
import { Annotations } from './annotations.js';
import { bindTfTools } from './tf-tools.js';
import { loadColormaps } from './tf-model.js';
import { SlicePanes } from './slice-panes.js';

const $ = (id) => document.getElementById(id);
const disposer = new Disposer();
const canvas = $('frame');
const ctx2d = canvas.getContext('2d');
// An access token in the address (?token=) moves to this tab's sessionStorage and out of the
// address bar at once, so no shared link, bookmark or history entry carries it.
let token = takeTokenFromUrl() || sessionStorage.getItem('peakcast-token') || '';

// What the client knows of its session; sent again in hello after a reconnect.
// The ray texture is the brush's (its strokes do not fit a URL): never in app.render.
const app = { volume: null, volumeInfo: null, camera: null, tf: null, render: {}, time: 0, cameraVersion: 1, welcomed: false };
const restored = readState();
if (restored) Object.assign(app, { volume: restored.volume, camera: restored.camera, tf: restored.tf, render: restored.render || {}, time: restored.time || 0 });

const stats = new StatsOverlay($('stats'));
const camera = new CameraController(canvas, disposer);
const tfEditor = new TfEditor({ canvas: $('tf-canvas'), color: $('tf-color'), remove: $('tf-delete'), undo: $('tf-undo'),
  redo: $('tf-redo'), preset: $('tf-preset'), iso: $('tf-iso'), point: $('tf-point') }, disposer);
const controls = new RenderControls($('controls'), disposer);
const picker = new VolumePicker({ select: $('volume-select'), path: $('volume-path'), open: $('volume-open'),
  progress: $('volume-progress'), info: $('volume-info') }, disposer);
const deleteButton = $('volume-delete');

function viewport() {
  const r = canvas.getBoundingClientRect();
  return { width: Math.max(1, Math.round(r.width)), height: Math.max(1, Math.round(r.height)), dpr: Math.min(window.devicePixelRatio || 1, 4) };
}

function helloFor() {
  const hello = { type: 'hello', viewport: viewport() };
  if (token) hello.token = token;
  if (app.volume) hello.volume = app.volume;
  const state = {};
  if (app.camera) state.camera = app.camera;
  if (app.tf) state.tf = { points: app.tf };
  if (Object.keys(app.render).length) state.render = app.render;
  if (app.time > 0) state.time = app.time;
  const rayTexture = brush.helloSpec();  // the first strokes; the rest follow as stroke messages
  if (rayTexture) state.render = { ...app.render, ray_texture: rayTexture };
  if (Object.keys(state).length) hello.state = state;
  return hello;
}

const stream = new Stream({ url: `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`, helloFor });
disposer.add(() => stream.dispose());
const codecPicker = new CodecPicker({ select: $('codec'), kbps: $('kbps'), stream, disposer });
const brush = new Brush({ section: $('ray-texture'), controls: $('rt-controls'), canvas, view: $('view'), outline: $('brush-outline'),
  previewBox: $('rt-preview-box'), preview: $('rt-preview'), legend: $('rt-legend'), status: $('rt-status'), undo: $('rt-undo'),
  clear: $('rt-clear') }, { stream, camera, scene: () => ({ camera: app.camera, volume: app.volumeInfo }) }, disposer);

function share() {
  const s = { volume: app.volume, camera: app.camera, tf: app.tf, render: app.render };
  if (app.time > 0) s.time = app.time;  // a time series' time point
  return s;
}

function titleOf(v) { return `peakcast — ${v.uploaded ? v.name : v.id}`; }

const timeControls = new TimeControls({ root: $('time'), slider: $('time-slider'), play: $('time-play'),
  rate: $('time-rate'), readout: $('time-readout') }, disposer);
disposer.listen(timeControls, 'time', (e) => stream.send({ type: 'time', time: e.detail }));

const annotations = new Annotations($('annotations'), disposer);
// Slice views beside the 3D view (the "3D + slices" layout): drawn by POST /api/slice.
const slices = new SlicePanes({ root: $('slices'), panes: ['x', 'y', 'z'].map((a) => ({ canvas: $(`slice-${a}`), caption: $(`slice-${a}-caption`) })) },
  { fetchSlice: (body) => fetch('/api/slice', { method: 'POST', body: JSON.stringify(body),
    headers: { 'Content-Type': 'application/json', ...(token ? { Authorization: `Bearer ${token}` } : {}) } }),
  scene: () => ({ volume: app.volume, tf: { points: app.tf }, time: app.time }) }, disposer);
disposer.listen($('layout-slices'), 'change', () => {
  slices.show($('layout-slices').checked);
  window.dispatchEvent(new Event('resize'));  // the 3D view's size changed: the server is told
});
const clip = new ClipControls({ boxOn: $('clip-box'), sliders: [...document.querySelectorAll('.clip-sliders input')],
  planeOn: $('clip-plane'), facing: $('clip-facing'), axes: [...document.querySelectorAll('.clip-axis')], flip: $('clip-flip'),
  offset: $('clip-offset'), readout: $('clip-readout') },
{ camera, canvas, project: (p) => (annotations.camera ? annotations.project(p, canvas.clientWidth, canvas.clientHeight) : null) }, disposer);
disposer.listen(clip, 'change', (e) => {
  if (e.detail) app.render.clip = e.detail; else delete app.render.clip;
  stream.send({ type: 'render', render: { clip: e.detail } });  // null removes it
  annotations.update({ clip: e.detail });
  writeState(share());
});
for (const box of document.querySelectorAll('#show-annotations input'))
  disposer.listen(box, 'change', () => annotations.update({ show: { ...annotations.show, [box.name]: box.checked } }));

function applyState(state, volumeInfo, volumes) {
  app.volume = volumeInfo.id;
  app.volumeInfo = volumeInfo;
  app.cameraVersion = state.versions?.camera ?? app.cameraVersion;
  app.camera = state.camera;
  app.tf = state.tf.points;
  const { ray_texture: _, ...render } = state.render || {};
  app.render = render;
  camera.set(state.camera, { home: !app.welcomed || !restored, silent: true });
  tfEditor.setVolume(volumeInfo);
  controls.setVolume(volumeInfo);
  tfEditor.set(state.tf.points);
  clip.setVolume(volumeInfo, render.clip);
  if (volumes) picker.show(volumes, volumeInfo);
  deleteButton.hidden = !volumeInfo.uploaded;
  const unit = lengthUnit(volumeInfo, state);
  probe.unit = unit;
  clip.unit = unit;
  controls.setUnit(unit);
  app.time = state.time ?? 0;
  timeControls.setVolume(volumeInfo, app.time);
  annotations.update({ camera: app.camera, volume: volumeInfo, tf: app.tf, clip: render.clip ?? null, unit });
  if (slices.info?.id !== volumeInfo.id) slices.setVolume(volumeInfo);
  else slices.refreshSoon();
  writeState(share());
}

// The colour-map presets are the server's maps (GET /api/colormaps), asked for once the session
// is let in (a server with tokens answers only then).
const fetchJson = async (url) => {
  const res = await fetch(url, { headers: token ? { Authorization: `Bearer ${token}` } : {} });
  if (!res.ok) throw new Error(`${url}: ${res.status}`);
  return res.json();
};
disposer.listen(stream, 'welcome', (e) => {
  loadColormaps(fetchJson);
  const w = e.detail;
  applyState(w.state, w.volume, w.volumes);
  app.volumes = w.volumes;
  controls.build(w.capabilities, w.state.render);
  brush.welcome(w.capabilities, w.state);
  codecPicker.welcome(w.capabilities, w.limits);
  app.welcomed = true;
  document.title = titleOf(w.volume);
});
// Each volume's camera and TF as last left: choosing it again from the menu brings them back
// (the server derives a TF and a view for every volume it opens), as a tabbed viewer keeps each tab.
const kept = new Map();
disposer.listen(stream, 'volume', (e) => {
  document.title = titleOf(e.detail.volume);  // the tab follows the volume
  // A new volume brings a new TF (derived from its histogram): said, and undo gives the old one back.
  const before = app.tf;
  if (app.volume && app.tf) kept.set(app.volume, { camera: structuredClone(app.camera), tf: structuredClone(app.tf) });
  // The old volume's picture goes now (not under the new box and colour bar until the new volume's
  // first frame), and a frame of it still on its way is not drawn.
  app.framesFrom = e.detail.state.versions;
  ctx2d.clearRect(0, 0, canvas.width, canvas.height);
  canvas.dataset.final = 'false';
  // A volume opened by path or uploaded stays in the menu after switching to another.
  if (!app.volumes.some((v) => v.id === e.detail.volume.id)) app.volumes = [...app.volumes, e.detail.volume];
  applyState(e.detail.state, e.detail.volume, app.volumes);
  camera.set(e.detail.state.camera, { home: true, silent: true });
  brush.volumeChanged(e.detail.state);
  probe.reset();
  if (before) tfEditor.remember(before);
  const name = e.detail.volume.uploaded ? e.detail.volume.name : e.detail.volume.id;
  const back = kept.get(e.detail.volume.id);
  if (back) {  // sent as edits: the server draws them, the share link keeps them
    camera.set(back.camera);
    tfEditor.set(back.tf, { silent: false });
    $('tf-note').textContent = `${name}: the view and TF you left it with (undo brings back the previous TF)`;
    return;
  }
  $('tf-note').textContent = `TF derived from ${name}'s histogram (undo brings back the previous one)`;
});
disposer.listen(stream, 'loading', (e) => picker.loading(e.detail));
disposer.listen(stream, 'stroke_ack', (e) => brush.sync.onAck(e.detail));
disposer.listen(stream, 'pong', (e) => brush.sync.onPong(e.detail));
// What the scene asks for that it will not get (peak finding with a TF without a peak): shown
// for as long as the server says so, gone with the next frame that has no warning.
const warningEl = $('warning');
// A pyramid held coarser than its finest level: the view at rest is drawn again at the finest,
// brick by brick (docs/chunked-volumes.md); the line under the volume picker says how far.
const refineEl = $('volume-progress');
const refining = (text) => {  // the picker's own loading text wins
  if (!text && !refineEl.dataset.refining) return;
  if (text && refineEl.textContent !== '' && !refineEl.dataset.refining) return;
  refineEl.textContent = text;
  refineEl.dataset.refining = text ? '1' : '';
};
disposer.listen(stream, 'refining', (e) => refining(`full resolution: ${Math.floor(100 * e.detail.fraction)}% of ${e.detail.bricks} bricks`));
disposer.listen(stream, 'stats', (e) => {
  if (e.detail.refining) refining('full resolution: starting…');
  else if (refineEl.dataset.refining) refining('');
  stats.stats(e.detail);
  if (e.detail.time !== undefined && e.detail.time !== app.time) {
    app.time = e.detail.time;
    slices.refreshSoon();
    writeState(share());
  }
  timeControls.drawn(e.detail.time);
  $('variant').textContent = e.detail.variant;
  const warnings = e.detail.warnings ?? [];
  warningEl.textContent = warnings.join('\n');
  warningEl.hidden = warnings.length === 0;
});
const errorEl = $('error');
let errorTimer = 0;
disposer.add(() => clearTimeout(errorTimer));
disposer.listen(stream, 'error', (e) => {
  console.warn('peakcast:', e.detail.code, e.detail.message);
  brush.sync.onError(e.detail);  // a refused stroke or texture: the brush resends its list
  if (e.detail.message?.startsWith('time')) timeControls.failed();  // a time point refused or unreadable
  if (e.detail.code === 'volume_error') return picker.failed(e.detail.message);
  if (e.detail.code === 'unauthorized') return;  // the status banner and token form say it
  if (e.detail.message?.startsWith('probe: ')) return probe.failed(e.detail.message);  // said under the view
  errorEl.textContent = `${e.detail.code}: ${e.detail.message}`;  // what the server refused, and why
  errorEl.hidden = false;
  clearTimeout(errorTimer);
  errorTimer = setTimeout(() => { errorEl.hidden = true; }, 8000);
});
disposer.listen(errorEl, 'click', () => { errorEl.hidden = true; });

disposer.listen(stream, 'frame', (e) => {
  const { frame, bitmap } = e.detail;
  const from = app.framesFrom;  // versions the volume shown started at
  if (from && (frame.cameraVersion < from.camera || frame.tfVersion < from.tf)) return bitmap.close();
  const vp = viewport();
  const w = Math.round(vp.width * vp.dpr), h = Math.round(vp.height * vp.dpr);
  if (canvas.width !== w || canvas.height !== h) {  // resizing reallocates and clears: only on change
    canvas.width = w;
    canvas.height = h;
  }
  ctx2d.imageSmoothingEnabled = true;
  ctx2d.drawImage(bitmap, 0, 0, canvas.width, canvas.height);  // interactive frames are upscaled
  bitmap.close();
  canvas.dataset.frames = String((+canvas.dataset.frames || 0) + 1);
  canvas.dataset.final = String(frame.final);
  canvas.dataset.cameraVersion = String(frame.cameraVersion);
  canvas.dataset.tfVersion = String(frame.tfVersion);
  canvas.dataset.renderVersion = String(frame.renderVersion);
  canvas.dataset.png = String(frame.png);
  stats.frameShown(frame);
});

const statusEl = $('status'), tokenForm = $('token-form');
disposer.listen(stream, 'status', async (e) => {
  const s = e.detail;
  statusEl.hidden = s.state === 'live';
  statusEl.className = 'banner' + (s.state === 'connecting' ? ' info' : '');
  document.body.dataset.status = s.state;
  if (s.state !== 'live') brush.sync.disconnected();
  if (s.state === 'connecting') statusEl.textContent = 'connecting…';
  if (s.state === 'disconnected') {
    let reason = s.reason;
    try {  // a refused upgrade (session cap) shows no reason to a WebSocket: ask the server
      const h = await (await fetch('/api/health')).json();
      if (h.max_sessions && h.sessions >= h.max_sessions) reason = `server full (${h.sessions} sessions)`;
    } catch { /* server down */ }
    statusEl.textContent = `disconnected: ${reason} — reconnecting in ${(s.retryMs / 1000).toFixed(1)} s`;
  }
  if (s.state === 'refused') {
    statusEl.textContent = 'refused: a valid access token is required';
    tokenForm.hidden = false;
    statusEl.style.top = '30%';
  }
});
disposer.listen(tokenForm, 'submit', (e) => {
  e.preventDefault();
  token = $('token-input').value;
  sessionStorage.setItem('peakcast-token', token);
  tokenForm.hidden = true;
  stream.refused = null;
  stream.connect();
});

disposer.listen(camera, 'change', (e) => {
  app.camera = e.detail;
  annotations.update({ camera: app.camera });
  app.cameraVersion++;
  stats.inputSent(app.cameraVersion);
  stream.send({ type: 'camera', camera: e.detail });
  writeState(share());
});
disposer.listen(tfEditor, 'change', (e) => {
  app.tf = e.detail.points;
  annotations.update({ tf: app.tf });
  $('tf-note').textContent = '';
  slices.refreshSoon();
  stream.send({ type: 'tf', tf: { points: e.detail.points }, version: e.detail.version });
  writeState(share());
});
disposer.listen(controls, 'change', (e) => {
  for (const [k, v] of Object.entries(e.detail)) if (v === null) delete app.render[k]; else app.render[k] = v;
  stream.send({ type: 'render', render: e.detail });
  writeState(share());
});
disposer.listen(picker, 'pick', (e) => stream.send({ type: 'volume', volume: e.detail }));
// An upload can be deleted from the viewer (DELETE /api/volumes/ID): the server moves every viewer
// of it to its default volume; the menu forgets it.
disposer.listen(deleteButton, 'click', async () => {
  const info = app.volumeInfo;
  if (!info?.uploaded) return;
  const res = await fetch(`/api/volumes/${encodeURIComponent(info.id)}`,
    { method: 'DELETE', headers: token ? { Authorization: `Bearer ${token}` } : {} });
  if (!res.ok) return picker.failed(`${info.name}: ${(await res.json().catch(() => ({}))).message ?? `HTTP ${res.status}`}`);
  app.volumes = app.volumes.filter((v) => v.id !== info.id);
  kept.delete(info.id);
  if (app.volumeInfo) picker.show(app.volumes.some((v) => v.id === app.volumeInfo.id) ? app.volumes : [...app.volumes, app.volumeInfo], app.volumeInfo);
});
const files = new FileBrowser({ button: $('volume-browse'), list: $('files') }, { token: () => token }, disposer);
disposer.listen(files, 'pick', (e) => picker.pick(e.detail.path, e.detail.bytes));
bindTfTools(tfEditor, { window: $('tf-window'), level: $('tf-level'), log: $('tf-log'), save: $('tf-save'),
  load: $('tf-load'), note: $('tf-note') }, disposer);
// A preset that needs a classification (the isosurface: peak finding, shaded) sets it.
disposer.listen(tfEditor, 'preset', (e) => {
  const { unlessNot, ...needs } = e.detail;  // unlessNot: only when the classification is that one
  if (!unlessNot || app.render.classification === unlessNot) controls.set(needs);
});
// The keyboard in the 3D view, the help overlay, the stats toggle, the collapsible panel.
const showStats = (show) => { toggle($('stats'), show); $('show-stats').checked = show; };
const probe = new Probe({ canvas, readout: $('probe-readout'), measure: $('measure'), pick: $('pick'), stream }, disposer);
disposer.listen(probe, 'points', (e) => annotations.update({ marks: e.detail }));
probe.picking = () => slices.shown;  // a click in the 3D view moves the slices' point to what it hit
disposer.listen(probe, 'pick', (e) => slices.setPoint(e.detail));
disposer.listen($('fullscreen'), 'click', () => toggleFullscreen());
bindViewKeys({ canvas, camera, help: $('help'), toggleStats: () => showStats($('stats').hidden),
  measure: () => probe.setMeasuring(!probe.measuring), measuring: () => probe.measuring, fullscreen: toggleFullscreen }, disposer);
disposer.listen($('help-button'), 'click', () => toggle($('help')));
disposer.listen($('help'), 'click', () => { $('help').hidden = true; });
disposer.listen($('show-stats'), 'change', () => showStats($('show-stats').checked));
const panel = bindPanel({ panel: $('panel'), button: $('panel-toggle') }, disposer);
// A file dropped on the view: uploaded, then opened like any volume.
const uploads = new DropUpload({ target: $('view'), overlay: $('drop-overlay'), progress: $('volume-progress') },
  { token: () => token }, disposer);
disposer.listen(uploads, 'uploaded', (e) => stream.send({ type: 'volume', volume: e.detail.id }));
for (const b of document.querySelectorAll('#view-buttons button[data-view]')) disposer.listen(b, 'click', () => camera.view(b.dataset.view));

let resizeTimer = 0;
disposer.listen(window, 'resize', () => {
  clearTimeout(resizeTimer);
  resizeTimer = setTimeout(() => stream.send({ type: 'viewport', ...viewport() }), 150);
});

// The screenshot: the server's still at the size asked for, with the annotations shown in the
// view (triad, box, scale bar, colour bar) drawn over it at the view's proportions, unless unticked.
disposer.listen($('shot'), 'click', async () => {
  const width = +$('shot-w').value, height = +$('shot-h').value;
  const scene = { volume: app.volume, camera: app.camera, tf: { points: app.tf }, render: { ...app.render, ...brush.sceneRender() }, image: { width, height } };
  const headers = { 'Content-Type': 'application/json' };
  if (token) headers.Authorization = `Bearer ${token}`;
  const res = await fetch('/api/render?format=png', { method: 'POST', headers, body: JSON.stringify(scene) });
  if (!res.ok) return alert(`screenshot failed: ${(await res.json()).message}`);
  let blob = await res.blob();
  if ($('shot-overlays').checked) {
    const still = await createImageBitmap(blob), out = document.createElement('canvas');
    Object.assign(out, { width, height });
    const g = out.getContext('2d'), s = height / Math.max(1, canvas.clientHeight);  // the view's text size, in proportion
    g.drawImage(still, 0, 0);
    still.close();
    g.setTransform(s, 0, 0, s, 0, 0);
    annotations.paint(g, width / s, height / s, { still: true });
    blob = await new Promise((resolve) => out.toBlob(resolve, 'image/png'));
  }
  const url = URL.createObjectURL(blob);
  const a = Object.assign(document.createElement('a'), { href: url, download: `peakcast-${app.volume}-${width}x${height}.png` });
  a.click();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
});
disposer.listen($('share'), 'click', async () => {
  const url = stateUrl(share());  // never carries the token (state-url.js)
  try { await navigator.clipboard.writeText(url); $('share-done').textContent = 'copied'; } catch { $('share-done').textContent = url; }
});

disposer.listen(window, 'pagehide', () => disposer.dispose());
window.peakcast = { app, stats, stream, camera, tfEditor, controls, brush, disposer, uploads, panel, annotations, probe, files, clip, timeControls, slices };  // for tests and the console
stream.connect();
