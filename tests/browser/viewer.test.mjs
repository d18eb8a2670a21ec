// The browser client as a first user meets it: each defect found in a first-time trial, fixed
// and held here. Debian's chromium through playwright-core, against a real server.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { frameCount, recordTexts, greyRamp, launch, openClient, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

const tf = (page) => page.evaluate(() => window.peakcast.tfEditor.points);
const cameraOf = (page) => page.evaluate(() => window.peakcast.app.camera);

test('undo stroke takes back the whole drag', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.check('input[name=brush-drag][value=paint]');
  const box = await page.locator('#frame').boundingBox();
  const drag = async (y) => {
    await page.mouse.move(box.x + box.width * 0.3, box.y + box.height * y);
    await page.mouse.down();
    await page.mouse.move(box.x + box.width * 0.7, box.y + box.height * y, { steps: 12 });
    await page.mouse.up();
  };
  await drag(0.4);
  const first = await page.evaluate(() => window.peakcast.brush.model.strokes.length);
  await drag(0.6);
  const both = await page.evaluate(() => window.peakcast.brush.model.strokes.length);
  assert.ok(first > 3 && both > first + 3, `strokes: ${first}, then ${both}: a drag paints many`);
  await page.click('#rt-undo');
  assert.equal(await page.evaluate(() => window.peakcast.brush.model.strokes.length), first, 'undo took back the second drag');
  await page.click('#rt-undo');
  assert.equal(await page.evaluate(() => window.peakcast.brush.model.strokes.length), 0, 'and then the first');
  await page.close();
});

test('the TF readout follows every edit, and the end points stay', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await greyRamp(page);
  const c = await page.locator('#tf-canvas').boundingBox();
  // Add a point in the middle, then drag it: the readout shows where it is now.
  await page.mouse.click(c.x + c.width / 2, c.y + c.height / 2);
  assert.match(await page.textContent('#tf-point'), /point 2 of 3/);
  await page.mouse.move(c.x + c.width / 2, c.y + c.height / 2);
  await page.mouse.down();
  await page.mouse.move(c.x + c.width * 0.6, c.y + c.height * 0.25, { steps: 4 });
  await page.mouse.up();
  const p = (await tf(page))[1];
  assert.match(await page.textContent('#tf-point'), new RegExp(`value ${p[0].toPrecision(5)}, opacity ${p[4].toFixed(2)}`));
  // Delete it from the keyboard: the readout counts what is left.
  await page.focus('#tf-canvas');
  await page.keyboard.press('Delete');
  assert.equal((await tf(page)).length, 2);
  assert.doesNotMatch(await page.textContent('#tf-point'), /of 3/);
  // The end points are not deleted (they set the TF beyond the range).
  await page.keyboard.press('PageDown');
  await page.keyboard.press('Delete');
  await page.keyboard.press('PageUp');
  await page.keyboard.press('Delete');
  assert.equal((await tf(page)).length, 2);
  await page.close();
});

test('the isosurface preset turns on peaks and shading, stays shown, and follows its isovalue', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.fill('#tf-iso', '120');
  await page.selectOption('#tf-preset', 'iso');
  assert.equal(await page.inputValue('#tf-preset'), 'iso', 'the menu shows the preset');
  assert.equal(await page.inputValue('select[name=classification]'), 'peaks');
  assert.ok(await page.isChecked('input[name=shading]'));
  const peakAt = async () => (await tf(page)).reduce((a, q) => (q[4] > a[4] ? q : a))[0];
  assert.ok(Math.abs((await peakAt()) - 120) < 1e-6);
  await page.fill('#tf-iso', '180');  // typing a new isovalue moves the surface
  await page.waitForFunction(() => Math.abs(window.peakcast.tfEditor.points.reduce((a, q) => (q[4] > a[4] ? q : a))[0] - 180) < 1e-6);
  // An edit by hand: the menu no longer claims the preset.
  const c = await page.locator('#tf-canvas').boundingBox();
  await page.mouse.click(c.x + 10, c.y + c.height / 2);
  assert.equal(await page.inputValue('#tf-preset'), '');
  await page.close();
});

test('Enter opens a path; a refused path names no server folder; the message goes with the next try', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  // Raw voxels without their JSON sidecar: refused, naming what was asked for, not where it lies.
  await page.fill('#volume-path', 'nucleon.raw');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => /⚠/.test(document.querySelector('#volume-progress').textContent), null, { timeout: 20000 });
  const message = await page.textContent('#volume-progress');
  assert.match(message, /nucleon/);
  assert.ok(!message.includes('/tests/data') && !/\/(work|home|root|tmp)\//.test(message), message);
  // A folder of slices with one header (headsq/quarter.nhdr) opens as that volume.
  await page.fill('#volume-path', 'headsq');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'headsq', null, { timeout: 30000 });
  assert.doesNotMatch(await page.textContent('#volume-progress'), /⚠/);
  assert.match(await page.title(), /headsq/);
  await page.close();
});

test('numbers out of range are marked and never sent; fixing them clears the mark', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.selectOption('select[name=sampling]', 'differential');
  const sent = [];
  page.on('websocket', () => {});
  await page.evaluate(() => { window.__sent = []; const s = window.peakcast.stream; const send = s.send.bind(s); s.send = (m) => { window.__sent.push(m); send(m); }; });
  for (const [name, bad] of [['s_k', '0'], ['s_k', '-2'], ['step', '0'], ['step', '1e-9']]) {
    await page.fill(`input[name=${name}]`, bad);
    assert.equal(await page.getAttribute(`input[name=${name}]`, 'aria-invalid'), 'true', `${name} ${bad}`);
  }
  assert.deepEqual(await page.evaluate(() => window.__sent.filter((m) => m.type === 'render')), [], 'an invalid number was sent');
  await page.fill('input[name=s_k]', '0.5');
  assert.equal(await page.getAttribute('input[name=s_k]', 'aria-invalid'), 'false');
  assert.ok(await page.evaluate(() => window.__sent.some((m) => m.type === 'render' && m.render.s_k === 0.5)));
  await page.waitForTimeout(500);
  assert.ok(await page.isHidden('#error'), 'the server was never asked with a bad value');
  void sent;
  await page.close();
});

test('controls that do not apply are disabled and every control explains itself', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.selectOption('select[name=classification]', 'post');
  await page.selectOption('select[name=sampling]', 'uniform');
  assert.ok(await page.isDisabled('select[name=peak_mode]'));
  assert.ok(await page.isDisabled('select[name=max_peaks]'));
  assert.ok(await page.isDisabled('input[name=s_k]'));
  await page.selectOption('select[name=classification]', 'peaks');
  await page.selectOption('select[name=sampling]', 'differential');
  assert.ok(await page.isEnabled('select[name=peak_mode]'));
  assert.ok(await page.isEnabled('input[name=s_k]'));
  // A projection (offered because the server lists it) is drawn unshaded, every cell walked.
  assert.ok(await page.isEnabled('input[name=shading]'));
  await page.selectOption('select[name=classification]', 'mip');
  assert.ok(await page.isDisabled('input[name=shading]') && await page.isDisabled('input[name=space_skipping]'));
  await page.waitForFunction(() => /\+mip/.test(document.querySelector('#variant')?.textContent ?? ''), null,
    { timeout: 20000 });
  await page.selectOption('select[name=classification]', 'peaks');
  const untitled = await page.$$eval('#controls label', (ls) => ls.filter((l) => (l.title || '').length < 20).map((l) => l.textContent));
  assert.deepEqual(untitled, []);
  // Each links to docs/scenes.md, which the server serves beside the client.
  const links = await page.$$eval('#controls label', (ls) => ls.map((l) => l.querySelector('a.doc')?.href));
  assert.ok(links.length >= 10 && links.every((h) => h?.endsWith('/docs/scenes.md#render')), String(links));
  const doc = await page.evaluate(async (h) => { const r = await fetch(h); return [r.status, await r.text()]; }, links[0]);
  assert.equal(doc[0], 200);
  assert.match(doc[1], /### `render`/);
  await page.close();
});

test('the 3D view takes the keyboard; ? shows the help; S hides the stats', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const home = await cameraOf(page);
  await page.focus('#frame');
  await page.keyboard.press('ArrowRight');
  await page.waitForFunction((e) => JSON.stringify(window.peakcast.app.camera.eye) !== JSON.stringify(e), home.eye);
  const turned = await cameraOf(page);
  const d = (c) => Math.hypot(...c.eye.map((x, i) => x - c.center[i]));
  assert.ok(Math.abs(d(turned) - d(home)) < 1e-6 * d(home), 'an orbit keeps the distance');
  await page.keyboard.press('+');
  await page.waitForFunction((dist) => {
    const c = window.peakcast.app.camera;
    return Math.hypot(...c.eye.map((x, i) => x - c.center[i])) < dist * 0.95;
  }, d(home));
  await page.keyboard.press('r');
  await page.waitForFunction((e) => JSON.stringify(window.peakcast.app.camera.eye) === JSON.stringify(e), home.eye);
  await page.keyboard.press('?');
  assert.ok(await page.isVisible('#help'));
  await screenshot(page, 'help');
  await page.keyboard.press('Escape');
  assert.ok(await page.isHidden('#help'));
  await page.keyboard.press('s');
  assert.ok(await page.isHidden('#stats'));
  assert.equal(await page.isChecked('#show-stats'), false);
  await page.check('#show-stats');
  assert.ok(await page.isVisible('#stats'));
  await page.close();
});

test('opening a volume shows how much of it the server has read', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  // Every text the progress line shows, and every loading message the server sends.
  const shownTexts = await recordTexts(page, '#volume-progress');
  await page.evaluate(() => {
    window.__loading = [];
    window.peakcast.stream.addEventListener('loading', (e) => window.__loading.push(e.detail));
  });
  await page.fill('#volume-path', 'HeadMRVolume.mhd');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'HeadMRVolume.mhd', null, { timeout: 30000 });
  const loading = await page.evaluate(() => window.__loading);
  assert.ok(loading.length > 0 && loading.at(-1).fraction === 1, JSON.stringify(loading));
  assert.ok(loading.every((m) => m.volume === 'HeadMRVolume.mhd'));
  const shown = await shownTexts();
  assert.ok(shown.some((t) => /loading HeadMRVolume\.mhd… read, preparing/.test(t)), JSON.stringify(shown));
  assert.equal(await page.textContent('#volume-progress'), '');
  // A fraction under 1 is a whole percentage, also for a load no pick started (a first hello's).
  await page.evaluate(() => window.peakcast.stream.dispatchEvent(new CustomEvent('loading', { detail: { volume: 'big.nrrd', fraction: 0.427 } })));
  assert.match(await page.textContent('#volume-progress'), /^loading big\.nrrd… 42%$/);
  await page.close();
});

test('switching volume says the TF changed, and undo brings the old one back', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await greyRamp(page);
  const ramp = await tf(page);
  await page.fill('#volume-path', 'nucleon.nhdr');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'nucleon.nhdr', null, { timeout: 30000 });
  assert.match(await page.textContent('#tf-note'), /TF derived from nucleon.nhdr/);
  assert.notDeepEqual(await tf(page), ramp);
  await page.click('#tf-undo');
  assert.deepEqual(await tf(page), ramp);
  await page.close();
});

test('a screenshot carries the annotations shown in the view, or the bare still when unticked', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.fill('#shot-w', '320');
  await page.fill('#shot-h', '240');
  const shoot = async () => {
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#shot')]);
    return Buffer.concat(await (await download.createReadStream()).toArray()).toString('base64');
  };
  // Pixels that differ from the REST still of the same scene (fetched in the page) by more than 40 levels.
  const differing = (b64) => page.evaluate(async (b64) => {
    const { app } = window.peakcast;
    const scene = { volume: app.volume, camera: app.camera, tf: { points: app.tf }, render: app.render, image: { width: 320, height: 240 } };
    const res = await fetch('/api/render?format=png', { method: 'POST', body: JSON.stringify(scene) });
    const pixels = async (blob) => {
      const bmp = await createImageBitmap(blob), c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
      g.drawImage(bmp, 0, 0);
      return g.getImageData(0, 0, bmp.width, bmp.height).data;
    };
    const a = await pixels(await res.blob()), b = await pixels(new Blob([Uint8Array.from(atob(b64), (c) => c.charCodeAt(0))]));
    let n = 0;
    for (let i = 0; i < a.length; i += 4) n += Math.max(...[0, 1, 2].map((c) => Math.abs(a[i + c] - b[i + c]))) > 40;
    return n;
  }, b64);
  const withOverlays = await differing(await shoot());
  assert.ok(withOverlays > 500, `the annotations drew ${withOverlays} pixels`);
  await page.uncheck('#shot-overlays');
  assert.equal(await differing(await shoot()), 0, 'unticked: the bare still');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('switching volume takes the old picture away at once and draws no frame of it after', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.evaluate(() => {
    const canvas = document.querySelector('#frame'), ctx = canvas.getContext('2d');
    window.__switch = null;
    window.peakcast.stream.addEventListener('volume', (e) => {  // runs after the viewer's own listener
      const d = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
      let ink = 0;
      for (let i = 3; i < d.length; i += 4) ink += d[i];
      window.__switch = { final: canvas.dataset.final, ink, versions: e.detail.state.versions };
    });
  });
  assert.ok(+(await page.getAttribute('#frame', 'data-frames')) > 0);
  await page.fill('#volume-path', 'nucleon.nhdr');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => window.__switch, null, { timeout: 30000 });
  const sw = await page.evaluate(() => window.__switch);
  assert.equal(sw.final, 'false', 'no old frame marked final under the new volume');
  assert.equal(sw.ink, 0, 'the old picture was still shown');
  await waitFinal(page);
  // A frame of the old volume arriving late is not drawn (it may arrive: then it was dropped).
  const drawnVersions = await page.evaluate(() => +document.querySelector('#frame').dataset.cameraVersion);
  assert.ok(drawnVersions >= sw.versions.camera, `drew camera version ${drawnVersions} < ${sw.versions.camera}`);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a volume chosen again from the menu comes back with the camera and TF it was left with', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const first = await page.evaluate(() => window.peakcast.app.volumeInfo.id);
  await greyRamp(page);
  await page.focus('#frame');
  for (let i = 0; i < 3; i++) await page.keyboard.press('ArrowLeft');
  await page.waitForTimeout(300);
  const ramp = await tf(page), eye = await page.evaluate(() => window.peakcast.app.camera.eye);
  await page.fill('#volume-path', 'nucleon.nhdr');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'nucleon.nhdr', null, { timeout: 30000 });
  await waitFinal(page);
  await page.evaluate(() => {
    window.__sources = [];
    window.peakcast.stream.addEventListener('stats', (e) => window.__sources.push(e.detail.tf_source));
  });
  await page.selectOption('#volume-select', first);
  await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id === id, first, { timeout: 30000 });
  assert.deepEqual(await tf(page), ramp);
  assert.deepEqual(await page.evaluate(() => window.peakcast.app.camera.eye), eye);
  assert.match(await page.textContent('#tf-note'), /the view and TF you left it with/);
  // The server draws them: the frames end with the client's own TF, not one it derived.
  await page.waitForFunction(() => window.__sources.at(-1) === 'scene', null, { timeout: 30000 });
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('at 800 px the panel starts collapsed and the view keeps its width; at 1280x800 the view controls show', async () => {
  const narrow = await openClient(browser, server.url, { width: 800, height: 900 });
  await waitFinal(narrow);
  assert.ok(await narrow.isHidden('#panel'));
  const view = await narrow.locator('#frame').boundingBox();
  assert.ok(view.width >= 790, `view ${view.width} px wide of 800`);
  await screenshot(narrow, 'narrow_collapsed');
  await narrow.click('#panel-toggle');
  assert.ok(await narrow.isVisible('#panel'));
  await screenshot(narrow, 'narrow_open');
  await narrow.click('#panel-toggle');
  assert.ok(await narrow.isHidden('#panel'));
  await narrow.close();
  const laptop = await openClient(browser, server.url, { width: 1280, height: 800 });
  await waitFinal(laptop);
  for (const b of await laptop.$$('#view-buttons button')) {
    const r = await b.boundingBox();
    assert.ok(r && r.y + r.height <= 800, 'a view button below the fold');
  }
  await laptop.click('#view-buttons button[data-view="+z"]');
  await laptop.waitForFunction(() => Math.abs(window.peakcast.app.camera.eye[0] - window.peakcast.app.camera.center[0]) < 1e-6);
  await screenshot(laptop, 'laptop');
  assert.deepEqual(laptop.errors, []);
  await laptop.close();
});

test('the first view has contrast, an axes triad, the box, a scale bar and a colour bar; each can be hidden', async () => {
  const page = await openClient(browser, server.url, { width: 1280, height: 800 });
  await waitFinal(page);
  await page.waitForTimeout(100);
  // The picture: luminance spread over the frame (a dim grey plume scored 0.085 of 1; the bound
  // the docs' examples are held to is 0.06).
  const spread = await page.evaluate(() => {
    const c = document.querySelector('#frame'), t = document.createElement('canvas');
    t.width = 160; t.height = 100;
    const g = t.getContext('2d');
    g.drawImage(c, 0, 0, 160, 100);
    const d = g.getImageData(0, 0, 160, 100).data;
    const lum = [];
    for (let i = 0; i < d.length; i += 4) lum.push((0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2]) / 255);
    const m = lum.reduce((a, b) => a + b) / lum.length;
    return Math.sqrt(lum.reduce((a, b) => a + (b - m) ** 2, 0) / lum.length);
  });
  assert.ok(spread > 0.06, `contrast ${spread}`);
  // What the overlay drew where: the triad's three colours in the lower right corner, the box's
  // edges through their projected midpoints.
  const drawn = () => page.evaluate(() => {
    const a = window.peakcast.annotations, c = document.querySelector('#annotations');
    const g = c.getContext('2d'), dpr = c.width / c.clientWidth, w = c.clientWidth, h = c.clientHeight;
    const px = (x, y) => g.getImageData(Math.round(x * dpr), Math.round(y * dpr), 1, 1).data;
    const near = (x, y, test) => {
      for (let dy = -2; dy <= 2; dy++) for (let dx = -2; dx <= 2; dx++) if (test(px(x + dx, y + dy))) return true;
      return false;
    };
    let red = 0, green = 0, blue = 0;
    for (let y = h - 95; y < h - 8; y += 1)
      for (let x = w - 95; x < w - 8; x += 1) {
        const [r, gg, b, al] = px(x, y);
        if (al < 100) continue;
        if (r > 180 && gg < 140 && b < 140) red++;
        if (gg > 160 && r < 140 && b < 140) green++;
        if (b > 180 && r < 150) blue++;
      }
    const k = a.corners().map((p) => a.project(p, w, h));
    const mid = (i, j) => [(k[i][0] + k[j][0]) / 2, (k[i][1] + k[j][1]) / 2];
    const edges = [[0, 1], [0, 2], [0, 4], [7, 6], [7, 5], [7, 3]].filter(([i, j]) => near(...mid(i, j), (d) => d[3] > 40)).length;
    return { red, green, blue, edges };
  });
  const shown = await drawn();
  assert.ok(shown.red > 5 && shown.green > 5 && shown.blue > 5, JSON.stringify(shown));
  assert.ok(shown.edges >= 5, JSON.stringify(shown));
  await screenshot(page, 'annotations');
  for (const name of ['triad', 'box']) await page.uncheck(`#show-annotations input[name=${name}]`);
  await page.waitForTimeout(100);
  const hidden = await drawn();
  assert.ok(hidden.red + hidden.green + hidden.blue === 0 && hidden.edges === 0, JSON.stringify(hidden));
  await page.close();
});

test('the TF toolkit: colour maps, modality presets, window/level, histogram axis, save and load', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const derived = await tf(page);  // the server's automatic TF: clear up to its threshold
  await page.selectOption('#tf-preset', 'viridis');
  let p = await tf(page);
  assert.equal(p.length, 11);
  assert.deepEqual(p.at(-1).slice(1, 4).map((c) => Math.round(c * 255)), [253, 231, 37]);
  // The presets are the server's maps (GET /api/colormaps), not a copy of them.
  const maps = (await (await fetch(`${server.url}/api/colormaps`)).json()).colormaps;
  assert.deepEqual(p.map((q) => q.slice(1, 4)), maps.viridis);
  await page.selectOption('#tf-preset', 'coolwarm');
  assert.deepEqual((await tf(page)).map((q) => q.slice(1, 4)), maps.coolwarm);
  // A colour map over peak finding (an opacity ramp has no peak): pre-integrated instead, no warning.
  await page.selectOption('select[name=classification]', 'peaks');
  await page.waitForFunction(() => window.peakcast.app.render.classification === 'peaks');
  await page.selectOption('#tf-preset', 'magma');
  assert.equal(await page.inputValue('select[name=classification]'), 'preint');
  // A colour map's opacity starts where the automatic TF's does (the histogram's background split,
  // found alike): the values below it (a CT's air and noise) stay clear; the colours still span
  // the whole range.
  const magma = await tf(page), split = derived[derived.findIndex((q) => q[4] > 0) - 1][0];
  assert.ok(magma.filter((q) => q[0] < split - 1e-9 * Math.abs(split)).length >= 2, JSON.stringify([split, magma]));
  for (const q of magma) if (q[0] < split) assert.equal(q[4], 0, JSON.stringify([split, q]));
  assert.ok(magma.at(-1)[4] > 0.5);
  assert.deepEqual(magma.map((q) => q.slice(1, 4)), maps.magma);
  await page.selectOption('select[name=classification]', 'post');
  await page.selectOption('#tf-preset', 'grey');
  assert.equal(await page.inputValue('select[name=classification]'), 'post', 'other classifications stay');
  await page.selectOption('#tf-preset', 'ct-bone');
  assert.equal(await page.inputValue('select[name=classification]'), 'preint');
  assert.ok(await page.isChecked('input[name=shading]'));
  // Window/level: the same TF over another range.
  await page.selectOption('#tf-preset', 'grey');
  await page.fill('#tf-window', '100');
  await page.fill('#tf-level', '150');
  await page.locator('#tf-level').dispatchEvent('change');
  p = await tf(page);
  assert.deepEqual([p[0][0], p.at(-1)[0]], [100, 200]);
  // A window/level that cannot apply is marked and said, and changes nothing; undo still undoes
  // the window/level that did apply.
  for (const [field, value, why] of [['#tf-window', '-50', /window must be a number > 0/], ['#tf-window', '0', /> 0/],
    ['#tf-level', '100000', /misses the data's range/]]) {
    await page.fill('#tf-window', field === '#tf-window' ? value : '100');
    await page.fill('#tf-level', field === '#tf-level' ? value : '150');
    await page.locator(field).dispatchEvent('change');
    assert.equal(await page.getAttribute(field, 'aria-invalid'), 'true', `${field} ${value}`);
    assert.match(await page.textContent('#tf-note'), why);
    assert.deepEqual(await tf(page), p);
  }
  await page.click('#tf-undo');
  const undone = await tf(page);
  assert.notDeepEqual([undone[0][0], undone.at(-1)[0]], [100, 200]);
  await page.click('#tf-redo');
  assert.deepEqual(await tf(page), p);
  // The histogram's axis: linear draws less of the rare values than log.
  const ink = () => page.evaluate(() => {
    const c = document.querySelector('#tf-canvas'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) n += d[i] === 0x33 && d[i + 1] === 0x33 && d[i + 2] === 0x44;
    return n;
  });
  const logInk = await ink();
  await page.uncheck('#tf-log');
  assert.ok((await ink()) < logInk * 0.8, 'a linear axis drew as much as the log one');
  // Saved, edited, loaded back.
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#tf-save')]);
  const saved = JSON.parse(await (await download.createReadStream()).toArray().then((b) => Buffer.concat(b).toString()));
  assert.deepEqual(saved.points, p);
  await page.selectOption('#tf-preset', 'magma');
  await page.setInputFiles('#tf-load', { name: 'tf.json', mimeType: 'application/json', buffer: Buffer.from(JSON.stringify({ tf: saved })) });
  await page.waitForFunction((want) => JSON.stringify(window.peakcast.tfEditor.points) === want, JSON.stringify(p));
  await page.setInputFiles('#tf-load', { name: 'bad.json', mimeType: 'application/json', buffer: Buffer.from('{"points": [[1, 2, 3]]}') });
  await page.waitForFunction(() => /⚠ bad.json/.test(document.querySelector('#tf-note').textContent));
  await page.close();
});
