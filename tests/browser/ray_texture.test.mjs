// The ray-texture brush in Debian's chromium against a real server: a stroke
// painted with real pointer events changes the streamed image inside its disk only (PNG finals,
// compared pixel for pixel), undo and clear bring the first image back, the preview shows the
// stroke, a reconnect replays the strokes, a long drag is paced and every stroke acknowledged,
// the volume mapping places a stroke on the box, and a server without the capability shows no
// paint UI.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { launch, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

// Before the page's scripts: keep the sockets, and log what the client sends and receives.
async function open({ width = 1000, height = 640, route = null } = {}) {
  const page = await browser.newPage({ viewport: { width, height } });
  page.errors = [];
  page.on('pageerror', (e) => page.errors.push(e.message));
  if (route) await page.routeWebSocket(/\/ws$/, route);
  await page.addInitScript(() => {
    window.__sockets = [];
    window.__sent = [];
    window.__got = [];
    window.__k = 0;  // one order over both logs (timestamps tie)
    const WS = window.WebSocket;
    window.WebSocket = class extends WS {
      constructor(...a) {
        super(...a);
        window.__sockets.push(this);
        this.addEventListener('message', (e) => { if (typeof e.data === 'string') window.__got.push({ t: performance.now(), k: window.__k++, m: JSON.parse(e.data) }); });
      }
      send(data) {
        if (typeof data === 'string') window.__sent.push({ t: performance.now(), k: window.__k++, m: JSON.parse(data) });
        super.send(data);
      }
    };
    // The render version the server is at once it has read everything sent: the welcome's, +1
    // per render and stroke message (every one in these tests is accepted).
    window.__renderVersion = () => {
      const w = window.__got.filter((g) => g.m.type === 'welcome').at(-1);
      return w.m.state.versions.render + window.__sent.filter((s) => s.k > w.k && (s.m.type === 'render' || s.m.type === 'stroke')).length;
    };
  });
  await page.goto(server.url);
  await waitFinal(page);
  return page;
}

const frameState = (page) => page.evaluate(() => {
  const d = document.querySelector('#frame').dataset;
  return { frames: +d.frames, render: +d.renderVersion };
});

// A final frame (PNG unless `png` is false) showing everything sent so far: a frame rendered
// before the last stroke can arrive after its ack, so frames are told apart by render version.
// `exact`: that version and no later one, to tell a new session's frames from the last one the
// page drew before a reconnect (the old session was at a later version, and its final frame stays
// on the canvas until the new session's first frame is drawn).
async function finalPng(page, { png = true, exact = false } = {}) {
  await page.waitForFunction(([png, exact]) => {
    const d = document.querySelector('#frame').dataset;
    const v = +d.renderVersion, want = window.__renderVersion();
    return d.final === 'true' && (!png || d.png === 'true') && (exact ? v === want : v >= want);
  }, [png, exact], { timeout: 30000 });
  return frameState(page);
}

// Every stroke in the list acknowledged by the server.
const settled = (page, strokes) => page.waitForFunction((n) => {
  const s = document.querySelector('#ray-texture').dataset;
  return +s.strokes === n && +s.pending === 0;
}, strokes, { timeout: 30000 });

const snap = (page, name) => page.evaluate((n) => {
  const c = document.querySelector('#frame');
  (window.__snaps ??= {})[n] = { w: c.width, h: c.height, d: c.getContext('2d').getImageData(0, 0, c.width, c.height).data };
}, name);

// Pixels of snapshot b against a that differ by more than 1/255 in any channel: inside the
// stroke's disk (an ellipse of half-axes rx, ry pixels) less `margin` pixels, outside it beyond
// `margin`, and in all.
const compare = (page, a, b, disk = null) => page.evaluate(([a, b, disk]) => {
  const A = window.__snaps[a], B = window.__snaps[b];
  if (A.w !== B.w || A.h !== B.h) return { sizes: [A.w, A.h, B.w, B.h] };
  const r = { inside: 0, insideLit: 0, insideChanged: 0, outside: 0, outsideChanged: 0, changed: 0, maxOutside: 0 };
  for (let y = 0; y < A.h; y++) {
    for (let x = 0; x < A.w; x++) {
      const i = (y * A.w + x) * 4;
      const diff = Math.max(Math.abs(A.d[i] - B.d[i]), Math.abs(A.d[i + 1] - B.d[i + 1]), Math.abs(A.d[i + 2] - B.d[i + 2]));
      if (diff > 1) r.changed++;
      if (!disk) continue;
      const dx = (x + 0.5 - disk.cx) / disk.rx, dy = (y + 0.5 - disk.cy) / disk.ry, d = Math.hypot(dx, dy);
      const m = disk.margin / Math.min(disk.rx, disk.ry);
      if (d < 1 - m) { r.inside++; if (diff > 1) r.insideChanged++; if (Math.max(A.d[i], A.d[i + 1], A.d[i + 2]) > 1) r.insideLit++; }
      if (d > 1 + m) { r.outside++; if (diff > 1) r.outsideChanged++; r.maxOutside = Math.max(r.maxOutside, diff); }
    }
  }
  return r;
}, [a, b, disk]);

// The disk of the model's stroke k in frame pixels, and a margin of two texels and two pixels
// (the texture is read with linear filtering).
const diskOf = (page, k) => page.evaluate((k) => {
  const m = window.peakcast.brush.model, s = m.strokes[k], c = document.querySelector('#frame');
  const side = Math.max(m.width, m.height);
  return {
    cx: s.center[0] * c.width, cy: s.center[1] * c.height,
    rx: (s.radius * side * c.width) / m.width, ry: (s.radius * side * c.height) / m.height,
    margin: 2 * Math.max(c.width / m.width, c.height / m.height) + 2,
  };
}, k);

// PNG finals, then paint mode: the session gets an empty texture (snapshots 'none' and 'empty').
async function enterPaint(page) {
  assert.ok(await page.isVisible('#ray-texture'), 'the paint UI is missing');
  await page.evaluate(() => window.peakcast.stream.send({ type: 'quality', final_format: 'png' }));
  await finalPng(page);
  await snap(page, 'none');
  await page.check('input[name=brush-drag][value=paint]');
  const state = await finalPng(page);
  await snap(page, 'empty');
  return state;
}

async function brush(page, { channel = 'termination', mode = 'set', value = 0, radius = 0.1, falloff = 0, level = 0 } = {}) {
  await page.selectOption('select[name=brush-channel]', channel);
  await page.selectOption('select[name=brush-mode]', mode);
  for (const [name, v] of [['value', value], ['radius', radius], ['falloff', falloff], ['level', level]]) {
    await page.fill(`input[name=brush-${name}]`, String(v));
    await page.locator(`input[name=brush-${name}]`).dispatchEvent('change');  // a typed number commits on change
  }
  assert.deepEqual(await page.evaluate(() => { const { drag, mapping, ...s } = window.peakcast.brush.controls.settings; return s; }),
    { channel, mode, value, radius, falloff, level });
}

test('a stroke changes the image inside its disk only; undo and clear restore it; the preview shows it', async () => {
  const page = await open();
  const before_ = await enterPaint(page);
  assert.equal((await compare(page, 'none', 'empty')).changed, 0, 'an empty texture changed the image');
  await page.evaluate(() => { window.__snaps.A = window.__snaps.empty; });
  await brush(page, { channel: 'termination', mode: 'set', value: 0, radius: 0.1, falloff: 0 });
  const box = await page.locator('#frame').boundingBox();
  const at = { x: box.x + box.width * 0.45, y: box.y + box.height * 0.5 };  // on the plume
  await page.mouse.move(at.x, at.y);
  await page.mouse.down();
  await page.mouse.up();
  await settled(page, 1);
  const acks = await page.evaluate(() => window.__got.filter((g) => g.m.type === 'stroke_ack').map((g) => g.m));
  assert.deepEqual(acks, [{ type: 'stroke_ack', seq: 1, strokes: 1 }]);
  const strokes = await page.evaluate(() => window.__sent.filter((s) => s.m.type === 'stroke').map((s) => s.m));
  assert.equal(strokes.length, 1, 'one pointerdown, one stroke');
  assert.deepEqual({ ...strokes[0].stroke, center: undefined }, { channel: 'termination', center: undefined, radius: 0.1, falloff: 0, value: 0, mode: 'set', level: 0 });
  const stroked = await finalPng(page);
  assert.equal(stroked.render, before_.render + 1, 'a stroke bumps the render version once');
  await snap(page, 'B');
  const disk = await diskOf(page, 0);
  const c = await compare(page, 'A', 'B', disk);
  console.log(`stroke: disk centre (${disk.cx.toFixed(1)}, ${disk.cy.toFixed(1)}) radius ${disk.rx.toFixed(1)}x${disk.ry.toFixed(1)} px, margin ${disk.margin.toFixed(1)} px;`,
    `inside ${c.insideChanged}/${c.inside} changed (${c.insideLit} not black before), outside ${c.outsideChanged}/${c.outside} changed (max ${c.maxOutside}/255)`);
  assert.equal(c.outsideChanged, 0, `pixels outside the disk changed: ${JSON.stringify(c)}`);
  assert.ok(c.insideChanged > 0.5 * c.inside, `too few pixels changed inside the disk: ${JSON.stringify(c)}`);
  // Termination 0 stops every ray before its first sample: whatever the volume showed there goes.
  assert.ok(c.insideChanged >= 0.95 * c.insideLit, `lit pixels left inside the disk: ${JSON.stringify(c)}`);

  // The preview: the termination channel, black (0) at the stroke, white (0.996) elsewhere.
  const preview = await page.evaluate((s) => {
    const p = document.querySelector('#rt-preview'), g = p.getContext('2d');
    const px = (fx, fy) => [...g.getImageData(Math.floor(fx * p.width), Math.floor(fy * p.height), 1, 1).data];
    return { visible: !document.querySelector('#rt-preview-box').hidden, centre: px(s.center[0], s.center[1]), corner: px(0.02, 0.02),
      texel: window.peakcast.brush.model.at(Math.floor(s.center[0] * window.peakcast.brush.model.width), Math.floor(s.center[1] * window.peakcast.brush.model.height), 'termination') };
  }, strokes[0].stroke);
  assert.ok(preview.visible);
  // Clear of the colour bar and its labels (the bar's left edge is 30 px from the view's right, its
  // top label right-aligned 4 px left of it, about 30 px wide) and of the corner buttons.
  const [pbox, view] = await page.evaluate(() => [document.querySelector('#rt-preview-box'), document.querySelector('#view')]
    .map((e) => e.getBoundingClientRect().toJSON()));
  assert.ok(pbox.right <= view.right - 70 && pbox.top >= view.top + 36, `the preview at ${JSON.stringify(pbox)}`);
  assert.equal(preview.texel, 0);
  assert.ok(preview.centre[0] < 20 && preview.corner[0] > 240, `preview ${JSON.stringify(preview)}`);
  assert.match(await page.textContent('#rt-legend'), /1 stroke · 0 pending/);
  await page.mouse.move(at.x + 40, at.y - 30);  // the outline beside the stroke, for the screenshot
  await page.waitForTimeout(100);
  await screenshot(page, 'ray_texture_stroke');

  // Undo: the texture without the stroke, sent whole; the first image comes back.
  await page.click('#rt-undo');
  await settled(page, 0);
  await finalPng(page);
  await snap(page, 'C');
  const u = await compare(page, 'A', 'C');
  console.log(`undo: ${u.changed} pixels differ from the first image`);
  assert.equal(u.changed, 0, 'undo did not restore the image');
  const renders = await page.evaluate(() => window.__sent.filter((s) => s.m.type === 'render' && 'ray_texture' in s.m.render).map((s) => s.m.render.ray_texture));
  assert.deepEqual(renders.at(-1).strokes, []);

  // A drag paints strokes along its path; clear removes them all.
  await page.mouse.move(at.x - 60, at.y);
  await page.mouse.down();
  await page.mouse.move(at.x + 60, at.y + 20, { steps: 8 });
  await page.mouse.up();
  const n = await page.evaluate(() => window.peakcast.brush.model.strokes.length);
  assert.ok(n >= 3, `a 120-px drag at radius ${disk.rx.toFixed(0)} px painted ${n} strokes`);
  await settled(page, n);
  // The status counts the drag as one stroke (what one undo takes back), its dabs beside it.
  assert.match(await page.textContent('#rt-status'), new RegExp(`· 1 stroke \\(${n} dabs\\) · 0 pending`));
  await finalPng(page);
  await snap(page, 'D');
  assert.ok((await compare(page, 'A', 'D')).changed > 1000);
  await page.click('#rt-clear');
  await settled(page, 0);
  await finalPng(page);
  await snap(page, 'E');
  assert.equal((await compare(page, 'A', 'E')).changed, 0, 'clear did not restore the image');
  assert.ok(await page.isHidden('#rt-preview-box'), 'the preview goes with the last stroke');
  const corner = await page.evaluate(() => [...document.querySelector('#rt-preview').getContext('2d').getImageData(64, 50, 1, 1).data]);
  assert.ok(corner[0] > 240, 'the preview still shows a stroke after clear');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a reconnect replays the strokes: the first in hello, the rest as stroke messages', async () => {
  const page = await open();
  const start = await enterPaint(page);
  await brush(page, { channel: 'termination', value: 0.2, radius: 0.06, falloff: 0.5 });
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.move(box.x + box.width * 0.35, box.y + box.height * 0.45);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.5, box.y + box.height * 0.55, { steps: 6 });
  await page.mouse.up();
  const n = await page.evaluate(() => window.peakcast.brush.model.strokes.length);
  assert.ok(n >= 3, `${n} strokes`);
  await settled(page, n);
  const painted = await finalPng(page);
  await snap(page, 'P');
  // The hello carries 1 stroke here (1000 in use), so the replay path is the one a long list takes.
  const sockets = await page.evaluate(() => {
    window.peakcast.brush.sync.helloLimit = 1;
    window.__sent.length = 0;
    window.__got.length = 0;
    window.__sockets.at(-1).close();
    return window.__sockets.length;
  });
  await page.waitForFunction((k) => window.__sockets.length > k && document.body.dataset.status === 'live', sockets, { timeout: 20000 });
  await settled(page, n);
  const sent = await page.evaluate(() => window.__sent.map((s) => s.m));
  const hello = sent.find((m) => m.type === 'hello');
  assert.equal(hello.state.render.ray_texture.strokes.length, 1);
  assert.deepEqual(sent.filter((m) => m.type === 'stroke').map((m) => m.seq), Array.from({ length: n - 1 }, (_, i) => i + 2));
  const acks = await page.evaluate(() => window.__got.filter((g) => g.m.type === 'stroke_ack').map((g) => g.m));
  assert.deepEqual(acks.at(-1), { type: 'stroke_ack', seq: n, strokes: n });
  const welcome = await page.evaluate(() => window.__got.find((g) => g.m.type === 'welcome').m.state.render.ray_texture);
  assert.equal(welcome.strokes.length, 1, 'the welcome shows the texture the hello carried');
  await page.evaluate(() => window.peakcast.stream.send({ type: 'quality', final_format: 'png' }));
  const since = () => page.evaluate(() => {  // the welcome's render version, what was sent after it, the canvas
    const w = window.__got.filter((g) => g.m.type === 'welcome').at(-1);
    const { final, png, renderVersion } = document.querySelector('#frame').dataset;
    return { welcome: w.m.state.versions.render, sent: window.__sent.filter((s) => s.k > w.k && s.m.type !== 'ack').map((s) => s.m.type),
      shown: { final, png, renderVersion } };
  });
  const replayed = await finalPng(page, { exact: true }).catch(async () => assert.fail(`no final PNG of the new session's version: ${JSON.stringify(await since())}`));
  assert.equal(replayed.render, n, `the new session: version 1 with the hello's texture, +1 per stroke: ${JSON.stringify(await since())}`);
  await snap(page, 'Q');
  const c = await compare(page, 'P', 'Q');
  console.log(`reconnect: ${n} strokes replayed (1 in hello, ${n - 1} as stroke messages), ${c.changed} pixels differ`);
  assert.equal(c.changed, 0, 'the replayed texture renders differently');
  assert.ok(painted.render > start.render);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a long drag is paced below the server rate and every stroke is acknowledged', async () => {
  const page = await open();
  await page.check('input[name=brush-drag][value=paint]');
  await page.waitForFunction(() => document.querySelector('#ray-texture').dataset.strokes === '0');
  await brush(page, { channel: 'step', mode: 'multiply', value: 0.5, radius: 0.005, falloff: 0.5, level: 1 });
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.move(box.x + 20, box.y + 40);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) await page.mouse.move(box.x + 20 + i * 60, box.y + 40 + i * 50, { steps: 2 });
  await page.mouse.up();
  const n = await page.evaluate(() => window.peakcast.brush.model.strokes.length);
  assert.ok(n > 200, `only ${n} strokes`);
  await settled(page, n);
  const log = await page.evaluate(() => ({
    sends: window.__sent.filter((s) => s.m.type === 'stroke').map((s) => [s.t, s.m.seq, s.k]),
    acks: window.__got.filter((g) => g.m.type === 'stroke_ack').map((g) => [g.t, g.m.seq, g.m.strokes, g.k]),
    all: window.__sent.map((s) => s.t),
  }));
  assert.deepEqual(log.sends.map((s) => s[1]), Array.from({ length: n }, (_, i) => i + 1), 'every stroke sent once, in order');
  assert.deepEqual(log.acks.map((a) => a[1]), log.acks.map((a) => a[2]), 'the server holds exactly the strokes sent');
  let maxWindow = 0, maxInFlight = 0;
  for (const [t] of log.sends) maxWindow = Math.max(maxWindow, log.sends.filter((s) => s[0] >= t && s[0] < t + 1000).length);
  for (const [, seq, k] of log.sends) maxInFlight = Math.max(maxInFlight, seq - log.acks.filter((a) => a[3] < k).length);
  // The server's bucket (a burst of 500, then 250/s) over everything the page sent: never empty.
  let tokens = 500, last = log.all[0], least = 500;
  for (const t of log.all) { tokens = Math.min(500, tokens + ((t - last) * 250) / 1000) - 1; last = t; least = Math.min(least, tokens); }
  const seconds = (log.sends.at(-1)[0] - log.sends[0][0]) / 1000;
  console.log(`pacing: ${n} strokes in ${seconds.toFixed(2)} s, at most ${maxWindow} in any second, ${maxInFlight} in flight,`,
    `${log.all.length} messages in all, the server's bucket never below ${least.toFixed(0)} of 500`);
  assert.ok(least >= 0, 'the page sent faster than the server reads');
  assert.ok(maxInFlight <= 32, `${maxInFlight} strokes un-acknowledged at once`);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('volume mapping: a stroke sits where the ray enters the box; switching the mapping clears', async () => {
  const page = await open();
  await page.check('input[name=brush-drag][value=paint]');
  await brush(page, { channel: 'blend', value: 1, radius: 0.04, falloff: 0.3 });
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.click(box.x + box.width * 0.3, box.y + box.height * 0.3);
  await settled(page, 1);
  await page.selectOption('select[name=brush-mapping]', 'volume');
  await settled(page, 0);
  assert.match(await page.textContent('#rt-status'), /volume 512×256 · 0 strokes · 0 pending · mapping volume: 1 stroke cleared/);
  // Seen from +z (looking down -z at the box centre): the ray through the image centre enters
  // the +z face at its centre, u = 1/2 + atan2(0, 1) / 2 pi = 0.5, v = acos(0) / pi = 0.5.
  await page.click('#view-buttons button[data-view="+z"]');
  const version = await page.evaluate(() => window.peakcast.app.cameraVersion);
  await waitFinal(page, { cameraVersion: version });
  await page.mouse.click(box.x + box.width / 2, box.y + box.height / 2);
  await settled(page, 1);
  const s = await page.evaluate(() => window.peakcast.brush.model.strokes[0]);
  assert.ok(Math.abs(s.center[0] - 0.5) < 0.005 && Math.abs(s.center[1] - 0.5) < 0.005, `centre ${s.center}`);
  // A pixel whose ray misses the volume paints nothing.
  await page.mouse.click(box.x + 3, box.y + 3);
  await page.waitForTimeout(200);
  assert.equal(await page.evaluate(() => window.peakcast.brush.model.strokes.length), 1);
  await page.mouse.move(box.x + box.width * 0.55, box.y + box.height * 0.4);
  await page.waitForTimeout(100);
  await screenshot(page, 'ray_texture_volume');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the controls are labelled and a server without ray textures shows no paint UI', async () => {
  const page = await open();
  await page.check('input[name=brush-drag][value=paint]');
  const unlabelled = await page.evaluate(() => [...document.querySelectorAll('input, select, textarea, canvas')]
    .filter((el) => !(el.labels?.length || el.getAttribute('aria-label') || el.getAttribute('aria-labelledby')))
    .map((el) => el.id || el.name || el.tagName));
  assert.deepEqual(unlabelled, []);
  // Paint mode from the keyboard: the drag radios take the arrow keys.
  await page.focus('input[name=brush-drag][value=paint]');
  await page.keyboard.press('ArrowLeft');
  assert.equal(await page.evaluate(() => window.peakcast.brush.controls.settings.drag), 'orbit');
  await page.close();

  const old = await open({
    route: (ws) => {
      const up = ws.connectToServer();
      ws.onMessage((m) => up.send(m));
      up.onMessage((m) => {
        if (typeof m === 'string' && m.includes('"welcome"')) {
          const w = JSON.parse(m);
          w.capabilities.ray_texture = false;
          m = JSON.stringify(w);
        }
        ws.send(m);
      });
    },
  });
  assert.ok(await old.isHidden('#ray-texture'));
  assert.ok(await old.isHidden('#rt-preview-box'));
  assert.equal(await old.evaluate(() => window.peakcast.brush.painting), false);
  assert.deepEqual(await old.evaluate(() => window.__sent.filter((s) => s.m.type === 'stroke' || 'ray_texture' in (s.m.render ?? {})).length), 0);
  await old.close();
});

test('docs screenshot: the brush over the heptane plume', async () => {
  const page = await open({ width: 1280, height: 900 });
  await page.check('input[name=brush-drag][value=paint]');
  // Early termination at 5% opacity across the translucent cloud: those rays stop near its skin.
  await brush(page, { channel: 'termination', value: 0.05, radius: 0.05, falloff: 0.5 });
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.move(box.x + box.width * 0.5, box.y + box.height * 0.3);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width * 0.62, box.y + box.height * 0.55, { steps: 10 });
  await page.mouse.up();
  const n = await page.evaluate(() => window.peakcast.brush.model.strokes.length);
  await settled(page, n);
  await finalPng(page, { png: false });
  await page.evaluate(() => document.querySelector('#ray-texture').scrollIntoView());
  await page.mouse.move(box.x + box.width * 0.4, box.y + box.height * 0.66);
  await page.waitForTimeout(150);
  await screenshot(page, 'ray_texture_docs');  // docs/client-ray-texture.png is a copy of it
  assert.deepEqual(page.errors, []);
  await page.close();
});
