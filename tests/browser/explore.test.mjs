// Exploring: probing and measuring in the view, the data browser, fullscreen, and touch. Debian's
// chromium through
// playwright-core, against a real server. The probe's answers are checked against POST
// /api/probe of the same scene, which the server's unit tests check against closed forms.
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { ROOT, launch, recordTexts, openClient, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

// What POST /api/probe answers for the page's current scene at a device pixel.
const restProbe = (page, pixel, pick = 'surface') => page.evaluate(async ([pixel, pick]) => {
  const { app } = window.peakcast, r = document.querySelector('#frame').getBoundingClientRect();
  const scene = { volume: app.volume, camera: app.camera, tf: { points: app.tf }, render: app.render,
    image: { width: Math.round(r.width), height: Math.round(r.height) }, pixel, pick };
  const res = await fetch('/api/probe', { method: 'POST', body: JSON.stringify(scene) });
  return res.json();
}, [pixel, pick]);

test('the value and world position under the cursor show as it moves, as the server probes them', async () => {
  const page = await openClient(browser, server.url, { width: 1200, height: 700 });
  await waitFinal(page);
  const box = await page.locator('#frame').boundingBox();
  const px = [Math.floor(box.width / 2), Math.floor(box.height / 2)];
  await page.mouse.move(box.x + px[0] + 0.5, box.y + px[1] + 0.5);
  await page.waitForFunction(() => /^value .* at \(/.test(document.querySelector('#probe-readout').textContent));
  const shown = await page.evaluate(() => window.peakcast.probe.last);
  const rest = await restProbe(page, px);
  assert.ok(rest.hit, JSON.stringify(rest));
  for (const k of ['hit', 'value', 'distance', 'opacity', 'pick']) assert.equal(shown[k], rest[k], k);
  assert.deepEqual(shown.position, rest.position);
  const text = await page.textContent('#probe-readout');
  assert.ok(text.includes(String(+rest.value.toPrecision(4))), text);
  // The default pick is the first visible surface, and the readout says so; "half opacity" asks
  // for the point where the ray gets half opaque, which lies no nearer (and here deeper: the
  // demo's TF is translucent).
  assert.equal(rest.pick, 'surface');
  assert.match(text, /\(first surface\)/);
  await page.selectOption('#pick', 'half');
  await page.mouse.move(box.x + px[0] + 1.5, box.y + px[1] + 0.5);
  await page.mouse.move(box.x + px[0] + 0.5, box.y + px[1] + 0.5);
  await page.waitForFunction(() => /\(half opacity\)/.test(document.querySelector('#probe-readout').textContent));
  const half = await restProbe(page, px, 'half');
  await page.waitForFunction((d) => window.peakcast.probe.last?.distance === d, half.distance);
  assert.ok(half.distance > rest.distance, JSON.stringify([half, rest]));
  await page.selectOption('#pick', 'surface');
  // The top left corner looks past the volume: said so.
  await page.mouse.move(box.x + 3, box.y + 3);
  await page.waitForFunction(() => /nothing opaque/.test(document.querySelector('#probe-readout').textContent));
  await page.mouse.move(box.x - 20, box.y + 100);  // off the view: the readout goes
  await page.waitForFunction(() => document.querySelector('#probe-readout').hidden);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('measure: two clicks give the distance between the surfaces under them, drawn over the view', async () => {
  const page = await openClient(browser, server.url, { width: 1200, height: 700 });
  await waitFinal(page);
  const box = await page.locator('#frame').boundingBox();
  const a = [Math.floor(box.width * 0.45), Math.floor(box.height * 0.45)];
  const b = [Math.floor(box.width * 0.55), Math.floor(box.height * 0.6)];
  await page.click('#measure');
  assert.equal(await page.getAttribute('#measure', 'aria-pressed'), 'true');
  assert.match(await page.textContent('#probe-readout'), /click a first point/);
  await page.mouse.click(box.x + a[0] + 0.5, box.y + a[1] + 0.5);
  await page.waitForFunction(() => window.peakcast.probe.points.length === 1);
  await page.mouse.click(box.x + b[0] + 0.5, box.y + b[1] + 0.5);
  await page.waitForFunction(() => window.peakcast.probe.points.length === 2);
  const [pa, pb] = [await restProbe(page, a), await restProbe(page, b)];
  const expected = Math.hypot(...pa.position.map((v, i) => v - pb.position[i]));
  const measured = +(await page.getAttribute('#probe-readout', 'data-distance'));
  assert.ok(Math.abs(measured - expected) < 1e-9 * expected, `${measured} vs ${expected}`);
  assert.match(await page.textContent('#probe-readout'), new RegExp(`distance ${+expected.toPrecision(4)}`));
  // The line between them is drawn (yellow) on the overlay at its midpoint.
  await page.waitForTimeout(100);
  const yellowAtMid = () => page.evaluate(() => {
    const an = window.peakcast.annotations, c = document.querySelector('#annotations');
    const w = c.clientWidth, h = c.clientHeight, dpr = c.width / w;
    const [p, q] = an.marks.map((m) => an.project(m, w, h));
    const g = c.getContext('2d');
    const d = g.getImageData(Math.round(((p[0] + q[0]) / 2) * dpr) - 2, Math.round(((p[1] + q[1]) / 2) * dpr) - 2, 5, 5).data;
    for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] > 180 && d[i + 2] < 120 && d[i + 3] > 100) return true;
    return false;
  });
  assert.ok(await yellowAtMid(), 'the measure line is drawn');
  await screenshot(page, 'measure');
  // A drag still orbits and adds no point; M ends the measure and clears it.
  const before = await page.evaluate(() => window.peakcast.app.camera.eye);
  await page.mouse.move(box.x + 200, box.y + 200);
  await page.mouse.down();
  await page.mouse.move(box.x + 300, box.y + 220, { steps: 5 });
  await page.mouse.up();
  assert.notDeepEqual(await page.evaluate(() => window.peakcast.app.camera.eye), before);
  assert.equal(await page.evaluate(() => window.peakcast.probe.points.length), 2);
  await page.focus('#frame');
  await page.keyboard.press('m');
  assert.equal(await page.getAttribute('#measure', 'aria-pressed'), 'false');
  assert.equal(await page.evaluate(() => window.peakcast.probe.points.length), 0);
  // Esc ends measuring too, as it leaves a mode anywhere.
  await page.keyboard.press('m');
  assert.equal(await page.getAttribute('#measure', 'aria-pressed'), 'true');
  await page.keyboard.press('Escape');
  assert.equal(await page.getAttribute('#measure', 'aria-pressed'), 'false');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('fullscreen from its button and from F', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.click('#fullscreen');
  await page.waitForFunction(() => document.fullscreenElement === document.documentElement);
  await page.click('#fullscreen');
  await page.waitForFunction(() => document.fullscreenElement === null);
  await page.focus('#frame');
  await page.keyboard.press('f');
  await page.waitForFunction(() => document.fullscreenElement !== null);
  await page.keyboard.press('f');
  await page.waitForFunction(() => document.fullscreenElement === null);
  await page.close();
});

test('on a tablet: one finger orbits, two fingers pinch to zoom', async () => {
  const context = await browser.newContext({ viewport: { width: 1024, height: 768 }, hasTouch: true, isMobile: true });
  const page = await context.newPage();
  await page.goto(server.url);
  await waitFinal(page);
  const cdp = await context.newCDPSession(page);
  const box = await page.locator('#frame').boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  const touch = (type, points) => cdp.send('Input.dispatchTouchEvent', { type, touchPoints: points.map(([x, y], id) => ({ x, y, id })) });
  const cam = () => page.evaluate(() => window.peakcast.app.camera);
  const dist = (c) => Math.hypot(...c.eye.map((v, i) => v - c.center[i]));
  const start = await cam();
  // One finger across the view: the eye turns about the centre at the same distance.
  await touch('touchStart', [[cx - 100, cy]]);
  for (let i = 1; i <= 8; i++) await touch('touchMove', [[cx - 100 + i * 25, cy]]);
  await touch('touchEnd', []);
  await page.waitForFunction((e) => window.peakcast.app.camera.eye.some((v, i) => Math.abs(v - e[i]) > 1), start.eye);
  const orbited = await cam();
  assert.ok(Math.abs(dist(orbited) - dist(start)) < 1e-6 * dist(start), 'an orbit keeps the distance');
  // Two fingers moving apart: closer.
  await touch('touchStart', [[cx - 40, cy], [cx + 40, cy]]);
  for (let i = 1; i <= 8; i++) await touch('touchMove', [[cx - 40 - i * 15, cy], [cx + 40 + i * 15, cy]]);
  await touch('touchEnd', []);
  await page.waitForFunction((d) => {
    const c = window.peakcast.app.camera;
    return Math.hypot(...c.eye.map((v, i) => v - c.center[i])) < d * 0.9;
  }, dist(orbited));
  await screenshot(page, 'tablet');
  await context.close();
});

test('the data browser lists the data directories by relative names, looks into folders and opens a volume', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.click('#volume-browse');
  await page.waitForSelector('#files li button');
  const names = () => page.$$eval('#files li', (li) => li.map((e) => e.textContent));
  const top = await names();
  for (const n of ['🗂 headsq', '📁 scenes/', '▦ heptane_151.nrrd', '▦ nucleon.nhdr', '▦ HeadMRVolume.mhd'])
    assert.ok(top.includes(n), `${n} in ${top}`);
  assert.ok(!top.some((t) => t.includes('nucleon.raw')), 'a header\'s data file is not offered');
  assert.ok(!top.some((t) => t.includes('/work') || t.includes('tests/data')), `no server path: ${top}`);
  await page.click('#files button:text("📁 scenes/")');
  await page.waitForFunction(() => document.querySelector('#files li').textContent === 'data/scenes');
  assert.ok((await names()).includes('📁 good/'));
  await page.click('#files button:text("↑ ..")');
  await page.waitForFunction(() => document.querySelector('#files li').textContent === 'data/');
  const n = await page.evaluate(() => +(document.querySelector('#frame').dataset.frames || 0));
  const shown = await recordTexts(page, '#volume-progress');
  await page.click('#files button:text("▦ nucleon.nhdr")');
  assert.ok(await page.isHidden('#files'));
  await page.waitForFunction(() => window.peakcast.app.volumeInfo?.dims?.join('x') === '41x41x41');
  assert.ok((await shown()).some((t) => /^loading nucleon\.nhdr \(\d/.test(t)), JSON.stringify(await shown()));
  await waitFinal(page, { afterFrames: n });
  assert.equal(await page.textContent('#volume-progress'), '');
  assert.match(await page.title(), /nucleon/);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('clipping: a crop box and a plane from the panel and Ctrl+drag, honoured by the server and the still', async () => {
  const page = await openClient(browser, server.url, { width: 1280, height: 800, versions: true });
  await waitFinal(page);
  const { canvasSummary, difference } = await import('./harness.mjs');
  const before = await canvasSummary(page);
  const frames = () => page.evaluate(() => +(document.querySelector('#frame').dataset.frames || 0));
  // The crop box: its x-low slider to the middle.
  let n = await frames();
  await page.check('#clip-box');
  await page.$eval('.clip-sliders input', (s) => { s.value = String((+s.min + +s.max) / 2); s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => window.peakcast.app.render.clip?.box?.[0]?.[0] > 70);
  await waitFinal(page, { afterFrames: n, current: true });
  const cropped = await canvasSummary(page);
  assert.ok(difference(before, cropped) > 2, `the crop changed the picture: ${difference(before, cropped)}`);
  await screenshot(page, 'clip_box');
  // The plane facing the viewer, then moved by Ctrl+drag: the offset follows the drag.
  await page.uncheck('#clip-box');
  await page.click('#clip-facing');
  await page.waitForFunction(() => window.peakcast.app.render.clip?.plane && !window.peakcast.app.render.clip.box);
  const offset = () => page.evaluate(() => window.peakcast.clip.plane.offset);
  assert.equal(await offset(), 0);
  const box = await page.locator('#frame').boundingBox();
  await page.keyboard.down('Control');
  await page.mouse.move(box.x + 300, box.y + 400);
  await page.mouse.down();
  await page.mouse.move(box.x + 300, box.y + 300, { steps: 5 });
  await page.mouse.up();
  await page.keyboard.up('Control');
  assert.ok((await offset()) > 20, `Ctrl+drag up moved the plane further in: ${await offset()}`);
  n = await frames();
  await waitFinal(page, { afterFrames: n, current: true });
  await screenshot(page, 'clip_plane');
  // The server renders what the page asks: a still of the page's scene equals the view's frame
  // (both from the same render.clip), and a probe through the cut finds what lies behind it.
  const still = await page.evaluate(async () => {
    const { app } = window.peakcast, r = document.querySelector('#frame').getBoundingClientRect();
    const scene = { volume: app.volume, camera: app.camera, tf: { points: app.tf }, render: app.render,
      image: { width: Math.round(r.width), height: Math.round(r.height) } };
    const res = await fetch('/api/render?format=rgb', { method: 'POST', body: JSON.stringify(scene) });
    const rgb = new Uint8Array(await res.arrayBuffer());
    const c = document.querySelector('#frame'), g = c.getContext('2d');
    const shown = g.getImageData(0, 0, c.width, c.height).data;
    let diff = 0;
    for (let p = 0, q = 0; p < rgb.length; p += 3, q += 4) diff += Math.abs(rgb[p] - shown[q]) + Math.abs(rgb[p + 1] - shown[q + 1]);
    return { status: res.status, mean: diff / (rgb.length / 3) / 2, clip: app.render.clip };
  });
  assert.equal(still.status, 200);
  assert.ok(still.mean < 3, `the still and the view differ by ${still.mean} levels on average (JPEG)`);
  // Off again: the picture comes back.
  n = await frames();
  await page.uncheck('#clip-plane');
  await page.waitForFunction(() => !window.peakcast.app.render.clip);
  await waitFinal(page, { afterFrames: n, current: true });
  const again = await canvasSummary(page);
  assert.ok(difference(before, again) < 1, `without a clip the picture is the first one: ${difference(before, again)}`);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('clipping: the crop box\'s faces drag in the view', async () => {
  const page = await openClient(browser, server.url, { width: 1280, height: 800 });
  await waitFinal(page);
  await page.check('#clip-box');
  await page.waitForFunction(() => window.peakcast.app.render.clip?.box);
  const handle = (a, side) => page.evaluate(([a, side]) => {
    const { clip } = window.peakcast, f = clip.faces().find((q) => q.a === a && q.side === side);
    const r = document.querySelector('#frame').getBoundingClientRect(), s = clip.project(f.p);
    return { x: r.left + s[0], y: r.top + s[1], value: clip.box[side][a] };
  }, [a, side]);
  // The x-high face's handle, dragged towards the x-low one: the box shrinks along x only.
  const hi = await handle(0, 1), lo = await handle(0, 0);
  await page.mouse.move(hi.x, hi.y);
  await page.mouse.down();
  await page.mouse.move(hi.x + (lo.x - hi.x) * 0.4, hi.y + (lo.y - hi.y) * 0.4, { steps: 6 });
  await page.mouse.up();
  await page.waitForFunction((v) => window.peakcast.app.render.clip.box[1][0] < v - 20, hi.value);
  const box = await page.evaluate(() => window.peakcast.app.render.clip.box);
  const camera = await page.evaluate(() => window.peakcast.app.camera);
  assert.ok(Math.abs(box[1][0] - (hi.value - 0.4 * (hi.value - lo.value))) < 0.1 * (hi.value - lo.value), JSON.stringify(box));
  assert.deepEqual([box[0][1], box[0][2], box[1][1], box[1][2]], [0, 0, 150, 150], 'the other faces stay');
  assert.equal(box[0][0], 0);
  // The drag moved the face, not the camera.
  const n = await page.evaluate(() => +(document.querySelector('#frame').dataset.frames || 0));
  await waitFinal(page, { afterFrames: n - 1 });
  assert.deepEqual(await page.evaluate(() => window.peakcast.app.camera), camera);
  await screenshot(page, 'clip_box_drag');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('clipping: the crop box turned off and on comes back where it was; a new volume starts without it', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.check('#clip-box');
  await page.$eval('.clip-sliders input', (s) => { s.value = String((+s.min + +s.max) / 2); s.dispatchEvent(new Event('input')); });
  await page.waitForFunction(() => window.peakcast.app.render.clip?.box?.[0]?.[0] > 70);
  const box = await page.evaluate(() => window.peakcast.clip.box);
  const sliders = () => page.$$eval('.clip-sliders input', (s) => s.map((x) => +x.value));
  const set = await sliders();
  // Off: no clip sent, the sliders stay (disabled) where they were; on again: the same box.
  await page.uncheck('#clip-box');
  await page.waitForFunction(() => !window.peakcast.app.render.clip);
  assert.deepEqual(await sliders(), set);
  await page.check('#clip-box');
  await page.waitForFunction(() => window.peakcast.app.render.clip?.box);
  assert.deepEqual(await page.evaluate(() => window.peakcast.clip.box), box);
  // Another volume: the box was in the old one's world units; it goes, from the controls, the
  // state the server sends, and the share link.
  await page.fill('#volume-path', 'nucleon.nhdr');
  await page.press('#volume-path', 'Enter');
  await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'nucleon.nhdr', null, { timeout: 30000 });
  await waitFinal(page);
  assert.equal(await page.isChecked('#clip-box'), false);
  assert.equal(await page.evaluate(() => window.peakcast.app.render.clip), undefined);
  await page.waitForTimeout(400);  // the link is written 300 ms after the last change
  assert.ok(!decodeURIComponent(await page.evaluate(() => location.hash)).includes('clip'), 'the share link keeps no clip');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a time series: a slider, play and a readout; frames in order; the share link keeps the time point', async () => {
  const dir = mkdtempSync(path.join(os.tmpdir(), 'peakcast-series-'));
  const made = spawnSync('/usr/bin/python3', [path.join(ROOT, 'scripts/make_time_series.py'), path.join(dir, 'series.zarr'),
    '--times', '6', '--size', '24']);
  assert.equal(made.status, 0, String(made.stderr));
  const s = await startServer(['--data', dir]);
  try {
    const page = await openClient(browser, s.url);
    await waitFinal(page);
    assert.equal(await page.isVisible('#time'), false, 'heptane is one time point: no time controls');
    await page.evaluate(() => {
      window.__times = [];
      window.peakcast.stream.addEventListener('stats', (e) => window.__times.push(e.detail.time));
    });
    await page.fill('#volume-path', 'series.zarr');
    await page.press('#volume-path', 'Enter');
    await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'series.zarr', null, { timeout: 30000 });
    await page.waitForSelector('#time', { state: 'visible' });
    assert.equal(await page.textContent('#time-readout'), 't 0 of 0…5');
    await page.$eval('#time-slider', (el) => { el.value = '3'; el.dispatchEvent(new Event('input')); });
    await page.waitForFunction(() => window.peakcast.timeControls.time === 3, null, { timeout: 30000 });
    assert.equal(await page.textContent('#time-readout'), 't 3 of 0…5');
    await waitFinal(page);
    // Playing at 5 a second for 2 s: the time moves on, and no frame goes back; the clock may skip
    // a time point or two the server could not draw in time, across the wrap too (5 -> 1).
    const start = await page.evaluate(() => window.__times.length);
    await page.fill('#time-rate', '5');
    await page.click('#time-play');
    assert.equal(await page.getAttribute('#time-play', 'aria-pressed'), 'true');
    await page.waitForTimeout(2000);
    await page.click('#time-play');
    const played = (await page.evaluate(() => window.__times)).slice(start);
    const steps = played.filter((t, i) => i === 0 || t !== played[i - 1]);
    assert.ok(steps.length >= 3, JSON.stringify(played));
    for (let i = 1; i < steps.length; i++) {
      const ahead = (steps[i] - steps[i - 1] + 6) % 6;  // 5 would be one back
      assert.ok(ahead >= 1 && ahead <= 3, JSON.stringify(steps));
    }
    // The share link carries the time point; opening it starts there.
    await page.$eval('#time-slider', (el) => { el.value = '4'; el.dispatchEvent(new Event('input')); });
    await page.waitForFunction(() => window.peakcast.timeControls.time === 4, null, { timeout: 30000 });
    await page.waitForFunction(() => /state=/.test(location.hash));
    await page.waitForTimeout(400);  // the link is written 300 ms after the last change
    const link = await page.evaluate(() => location.href);
    const second = await openClient(browser, link);
    await second.waitForFunction(() => window.peakcast?.timeControls?.time === 4 && window.peakcast.app.volumeInfo?.id === 'series.zarr',
      null, { timeout: 30000 });
    await waitFinal(second);
    assert.equal(await second.textContent('#time-readout'), 't 4 of 0…5');
    await screenshot(second, 'time-series');
    assert.deepEqual(page.errors, []);
    assert.deepEqual(second.errors, []);
    await second.close();
    await page.close();
  } finally {
    await s.stop();
    rmSync(dir, { recursive: true, force: true });
  }
});
