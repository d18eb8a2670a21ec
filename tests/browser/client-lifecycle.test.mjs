// The client's lifecycle and input hygiene: reconnects release what the
// previous session held, decoded frames are always closed, the canvas is resized only when its
// size changes, the token never reaches a shared link, TF drags are coalesced per animation
// frame, keyboard control, labels, and server errors shown to the user.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { greyRamp, launch, openClient, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

// Before the page's scripts: keep every WebSocket and ImageBitmap the client makes, and let a
// test slow decoding down.
function instrument(page) {
  return page.addInitScript(() => {
    window.__sockets = [];
    const WS = window.WebSocket;
    window.WebSocket = class extends WS {
      constructor(...a) { super(...a); window.__sockets.push(this); }
    };
    window.__bitmaps = [];
    window.__decodeDelay = 0;
    const decode = window.createImageBitmap.bind(window);
    window.createImageBitmap = async (...a) => {
      const b = await decode(...a);
      window.__bitmaps.push(b);
      if (window.__decodeDelay) await new Promise((r) => setTimeout(r, window.__decodeDelay));
      return b;
    };
  });
}

async function open(url = server.url) {
  const page = await browser.newPage({ viewport: { width: 1000, height: 640 } });
  page.errors = [];
  page.on('pageerror', (e) => page.errors.push(e.message));
  await instrument(page);
  await page.goto(url);
  await waitFinal(page);
  return page;
}

// Records what the client sends from now on.
const recordSends = (page) => page.evaluate(() => {
  const s = window.peakcast.stream;
  window.__sent = [];
  const send = s.send.bind(s);
  s.send = (m) => { window.__sent.push(m); send(m); };
});
const sent = (page, type) => page.evaluate((t) => window.__sent.filter((m) => m.type === t), type);

test('reconnects do not grow what the page holds', async () => {
  const page = await open();
  const held = await page.evaluate(() => window.peakcast.disposer.size);
  for (let k = 1; k <= 3; k++) {
    const welcomes = await page.evaluate(() => window.__sockets.length);
    await page.evaluate(() => window.__sockets.at(-1).close());
    await page.waitForFunction((n) => window.__sockets.length > n && document.body.dataset.status === 'live', welcomes, { timeout: 20000 });
  }
  await page.waitForFunction(() => document.querySelector('#controls select') !== null);
  assert.equal(await page.evaluate(() => window.peakcast.disposer.size), held, 'listeners pile up with every welcome');
  // The controls of the last welcome still work, once each.
  await recordSends(page);
  await page.selectOption('#controls select[name=filter]', 'tricubic');
  await page.waitForTimeout(200);
  const renders = await sent(page, 'render');
  assert.deepEqual(renders.map((m) => m.render), [{ filter: 'tricubic' }]);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a frame decoded after the page is disposed is closed', async () => {
  const page = await open();
  const before_ = await page.evaluate(() => window.__bitmaps.length);
  await page.evaluate(() => { window.__decodeDelay = 400; window.peakcast.camera.view('+x'); });
  await page.waitForFunction((n) => window.__bitmaps.length > n, before_, { timeout: 20000 });
  await page.evaluate(() => window.dispatchEvent(new Event('pagehide')));  // what leaving the page does
  await page.waitForTimeout(900);
  const open_ = await page.evaluate(() => window.__bitmaps.filter((b) => b.width !== 0).length);
  assert.equal(open_, 0, 'an ImageBitmap was left open');
  await page.close();
});

test('the canvas is resized only when its size changes', async () => {
  const page = await open();
  await page.evaluate(() => {
    window.__resizes = 0;
    new MutationObserver((records) => { window.__resizes += records.length; })
      .observe(document.querySelector('#frame'), { attributes: true, attributeFilter: ['width', 'height'] });
  });
  const n = await page.evaluate(() => +document.querySelector('#frame').dataset.frames);
  await page.evaluate(() => window.peakcast.camera.view('+y'));
  const version = await page.evaluate(() => window.peakcast.app.cameraVersion);
  await waitFinal(page, { afterFrames: n, cameraVersion: version });
  assert.equal(await page.evaluate(() => window.__resizes), 0, 'frames of the same size resized the canvas');
  await page.setViewportSize({ width: 900, height: 600 });
  await page.waitForFunction(() => window.__resizes > 0, null, { timeout: 20000 });
  const size = await page.evaluate(() => { const c = document.querySelector('#frame'), r = c.getBoundingClientRect(); return [c.width, r.width]; });
  assert.equal(size[0], Math.round(size[1]), 'the canvas follows a window resize');
  await page.close();
});

test('the access token never appears in the address bar or a shared link', async () => {
  const guarded = await startServer(['--token', 's3cret-token']);
  try {
    const page = await open(guarded.url + '/?token=s3cret-token&keep=1');
    assert.doesNotMatch(await page.evaluate(() => location.href), /s3cret/);
    assert.match(await page.evaluate(() => location.search), /keep=1/, 'other parameters stay');
    await page.evaluate(() => { navigator.clipboard.writeText = async (t) => { window.__copied = t; }; });
    await page.click('#share');
    const link = await page.waitForFunction(() => window.__copied).then((h) => h.jsonValue());
    assert.doesNotMatch(link, /token|s3cret/);
    assert.match(link, /#state=/);
    await page.waitForTimeout(400);  // the state URL is written to the address bar after 300 ms
    assert.doesNotMatch(await page.evaluate(() => location.href), /s3cret/);
    const n = await page.evaluate(() => +document.querySelector('#frame').dataset.frames);
    await page.reload();  // the tab keeps the token: a reload still connects
    await waitFinal(page);
    assert.ok(n > 0);
    await page.close();
  } finally {
    await guarded.stop();
  }
});

test('a TF drag sends one TF per animation frame, and pointercancel ends it', async () => {
  const page = await open();
  await greyRamp(page);
  await recordSends(page);
  const tf = await page.locator('#tf-canvas').boundingBox();
  await page.mouse.move(tf.x + tf.width - 1, tf.y + 5);  // the grey ramp's last point
  await page.mouse.down();
  // 50 moves within one task: one animation frame.
  await page.evaluate(() => {
    const c = document.querySelector('#tf-canvas'), r = c.getBoundingClientRect();
    for (let i = 0; i < 50; i++)
      c.dispatchEvent(new PointerEvent('pointermove', { clientX: r.right - 1, clientY: r.top + 5 + i, bubbles: true }));
  });
  await page.waitForTimeout(300);
  assert.equal((await sent(page, 'tf')).length, 1, 'moves within one frame were not coalesced');
  const last = (await sent(page, 'tf'))[0];
  const points = await page.evaluate(() => window.peakcast.tfEditor.points);
  assert.deepEqual(last.tf.points, points, 'the coalesced message carries the newest points');
  // The browser cancels the gesture: later moves change nothing.
  await page.evaluate(() => document.querySelector('#tf-canvas').dispatchEvent(new PointerEvent('pointercancel', { bubbles: true })));
  await page.evaluate(() => {
    const c = document.querySelector('#tf-canvas'), r = c.getBoundingClientRect();
    c.dispatchEvent(new PointerEvent('pointermove', { clientX: r.left + 40, clientY: r.bottom - 2, bubbles: true }));
  });
  await page.waitForTimeout(200);
  assert.deepEqual(await page.evaluate(() => window.peakcast.tfEditor.points), points);
  assert.equal((await sent(page, 'tf')).length, 1);
  await page.mouse.up();
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the TF editor works from the keyboard', async () => {
  const page = await open();
  await greyRamp(page);
  await recordSends(page);
  const before_ = await page.evaluate(() => window.peakcast.tfEditor.points);
  await page.focus('#tf-canvas');
  await page.keyboard.press('PageDown');  // selects the first point
  assert.match(await page.textContent('#tf-point'), /point 1 of 2/);
  for (let i = 0; i < 5; i++) await page.keyboard.press('ArrowUp');
  await page.keyboard.press('Shift+ArrowRight');
  await page.waitForTimeout(200);
  const points = await page.evaluate(() => window.peakcast.tfEditor.points);
  assert.ok(Math.abs(points[0][4] - (before_[0][4] + 0.1)) < 1e-9, `opacity ${points[0][4]}`);
  const span = before_[1][0] - before_[0][0];
  assert.ok(Math.abs(points[0][0] - (before_[0][0] + 0.1 * span)) < 1e-6 * span, `value ${points[0][0]}`);
  const tfs = await sent(page, 'tf');
  assert.ok(tfs.length >= 1);
  assert.deepEqual(tfs.at(-1).tf.points, points);
  await page.keyboard.press('PageDown');
  assert.match(await page.textContent('#tf-point'), /point 2 of 2/);
  // Ctrl+Z undoes the last move (Shift+ArrowRight), as the undo button does; Ctrl+Shift+Z redoes it.
  await page.keyboard.press('Control+z');
  const undone = await page.evaluate(() => window.peakcast.tfEditor.points);
  assert.ok(Math.abs(undone[0][0] - before_[0][0]) < 1e-6 * span && Math.abs(undone[0][4] - points[0][4]) < 1e-9,
    JSON.stringify(undone));
  await page.keyboard.press('Control+Shift+Z');
  assert.deepEqual(await page.evaluate(() => window.peakcast.tfEditor.points), points);
  await page.close();
});

test('controls are labelled and the status is announced', async () => {
  const page = await open();
  const unlabelled = await page.evaluate(() => [...document.querySelectorAll('input, select, textarea, canvas')]
    .filter((el) => !(el.labels?.length || el.getAttribute('aria-label') || el.getAttribute('aria-labelledby')))
    .map((el) => el.id || el.name || el.tagName));
  assert.deepEqual(unlabelled, []);
  const status = await page.evaluate(() => { const s = document.querySelector('#status'); return [s.getAttribute('role'), s.getAttribute('aria-live')]; });
  assert.deepEqual(status, ['status', 'polite']);
  await page.close();
});

test('an error from the server is shown, not only logged', async () => {
  const page = await open();
  assert.ok(await page.isHidden('#error'));
  await page.evaluate(() => window.peakcast.stream.send({ type: 'render', render: { step: -1 } }));
  await page.waitForSelector('#error:not([hidden])', { timeout: 10000 });
  const text = await page.textContent('#error');
  assert.match(text, /step/, text);
  await screenshot(page, 'error_shown');
  await page.click('#error');
  assert.ok(await page.isHidden('#error'));
  await page.close();
});
