// The browser client in Debian's chromium against a real server.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { canvasSummary, difference, frameCount, greyRamp, launch, openClient, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

test('the page loads and a frame appears', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const s = await canvasSummary(page);
  assert.ok(s.lit > 0.05, `canvas nearly blank: ${s.lit}`);
  assert.match(await page.textContent('#stats'), /final/);
  assert.deepEqual(page.errors, []);
  await screenshot(page, 'loaded');
  await page.close();
});

test('a drag rotates: pixels change, interactive frames, then a final frame', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const before_ = await canvasSummary(page);
  const n = await frameCount(page);
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  const sawInteractive = page.waitForFunction(() => document.querySelector('#frame').dataset.final === 'false', null, { timeout: 20000 });
  for (let i = 1; i <= 15; i++) {
    await page.mouse.move(box.x + box.width / 2 + i * 12, box.y + box.height / 2 + i * 3);
    await page.waitForTimeout(20);
  }
  await page.mouse.up();
  await sawInteractive;
  const version = await page.evaluate(() => window.peakcast.app.cameraVersion);
  await waitFinal(page, { afterFrames: n, cameraVersion: version });
  const after_ = await canvasSummary(page);
  assert.ok(difference(before_, after_) > 2, 'the image did not change');
  await screenshot(page, 'rotated');
  await page.close();
});

test('dragging a TF point changes the image', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await greyRamp(page);
  const before_ = await canvasSummary(page);
  const n = await frameCount(page);
  const tf = await page.locator('#tf-canvas').boundingBox();
  // The grey ramp's last point sits at the top right: drag it down to a fifth of the opacity.
  await page.mouse.move(tf.x + tf.width - 1, tf.y + 5);
  await page.mouse.down();
  await page.mouse.move(tf.x + tf.width - 1, tf.y + tf.height * 0.8, { steps: 5 });
  await page.mouse.up();
  await waitFinal(page, { afterFrames: n + 1, currentTf: true });
  const after_ = await canvasSummary(page);
  // Less opacity: rays reach further into the plume. The image must change, whichever way.
  assert.ok(difference(before_, after_) > 0.5, `difference ${difference(before_, after_)}`);
  const points = await page.evaluate(() => window.peakcast.tfEditor.points);
  assert.equal(points.length, 2, 'the drag moved the existing point');
  assert.ok(points[1][4] < 0.4, `opacity ${points[1][4]}`);
  await page.close();
});

test('the first picture has a derived TF, and peak finding without a peak warns', async () => {
  const page = await openClient(browser, server.url, { versions: true });
  await waitFinal(page);
  assert.equal(await page.evaluate(() => window.peakcast.stats.last.stats.tf_source), 'auto');
  assert.ok(await page.isHidden('#warning'));
  // A ramp has no opacity peak: peak finding finds nothing, and the page says so.
  let n = await frameCount(page);
  await page.evaluate(() => window.peakcast.tfEditor.set([[0, 0, 0, 0, 0], [255, 1, 1, 1, 0.3]], { silent: false }));
  await page.selectOption('select[name=classification]', 'peaks');
  await waitFinal(page, { afterFrames: n + 1, current: true });
  await page.waitForSelector('#warning:not([hidden])', { timeout: 20000 });
  assert.match(await page.textContent('#warning'), /no opacity peak/);
  // The stats, the warning and the probe's readout never lie over each other, at 800x600 too.
  const frame = await page.locator('#frame').boundingBox();
  await page.mouse.move(frame.x + frame.width / 2, frame.y + frame.height / 2);
  await page.waitForSelector('#probe-readout:not([hidden])');
  for (const size of [null, { width: 800, height: 600 }]) {
    if (size) await page.setViewportSize(size);
    const rects = await page.$$eval('#stats, #warning, #probe-readout', (els) => els.map((e) => e.getBoundingClientRect().toJSON()));
    for (let i = 0; i < rects.length; i++)
      for (let j = i + 1; j < rects.length; j++) {
        const [a, b] = [rects[i], rects[j]];
        const overlap = a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;
        assert.ok(!overlap && a.width > 0 && b.width > 0, `overlays ${i} and ${j} collide at ${JSON.stringify(size)}: ${JSON.stringify(rects)}`);
      }
  }
  await screenshot(page, 'peaks_without_a_peak');
  // A volume with a long name stays inside the panel.
  const inside = await page.evaluate(() => {
    const s = document.querySelector('#volume-select');
    s.add(new Option('a volume with a very long name, as an upload or a DICOM series description has it '.repeat(3)));
    s.selectedIndex = s.options.length - 1;
    const r = s.getBoundingClientRect(), p = document.querySelector('#panel').getBoundingClientRect();
    return r.right <= p.right + 0.5 && r.left >= p.left;
  });
  assert.ok(inside, 'the volume menu overflows the panel');
  // Back to postclassification: the warning goes.
  n = await frameCount(page);
  await page.selectOption('select[name=classification]', 'post');
  await waitFinal(page, { afterFrames: n + 1, current: true });
  await page.waitForSelector('#warning', { state: 'hidden', timeout: 20000 });
  await page.close();
});

test('an isosurface preset with peak finding shows a surface', async () => {
  const page = await openClient(browser, server.url, { versions: true });
  await waitFinal(page);
  await greyRamp(page);
  const postclass = await canvasSummary(page);
  let n = await frameCount(page);
  await page.selectOption('select[name=classification]', 'peaks');
  await page.check('input[name=shading]');
  await page.fill('#tf-iso', '200');
  await page.selectOption('#tf-preset', 'iso');
  // The final frame of the preset's TF (the one before it may show the grey ramp with peaks on).
  await waitFinal(page, { afterFrames: n + 1, currentTf: true, current: true });
  await page.waitForFunction(() => /peaks/.test(document.querySelector('#variant').textContent), null, { timeout: 20000 });
  const peaks = await canvasSummary(page);
  const peakCount = await page.evaluate(() => window.peakcast.tfEditor.points.length);
  assert.equal(peakCount, 5);
  // An opaque shaded surface covers much of the plume; the same TF without peak finding barely shows.
  n = await frameCount(page);
  await page.selectOption('select[name=classification]', 'post');
  await waitFinal(page, { afterFrames: n + 1, current: true });
  const post = await canvasSummary(page);
  assert.ok(peaks.lit > 0.02 && peaks.lit > post.lit * 3, `lit ${peaks.lit} (peaks) vs ${post.lit} (post)`);
  assert.ok(difference(peaks, postclass) > 5);
  await page.selectOption('select[name=classification]', 'peaks');
  await waitFinal(page, { afterFrames: n + 2, current: true });
  await screenshot(page, 'isosurface_peaks');
  await page.close();
});

test('after a server restart the client reconnects and shows the same view', async () => {
  const own = await startServer();
  const page = await openClient(browser, own.url);
  await waitFinal(page);
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.move(box.x + 300, box.y + 300);
  await page.mouse.down();
  await page.mouse.move(box.x + 420, box.y + 260, { steps: 6 });
  await page.mouse.up();
  const version = await page.evaluate(() => window.peakcast.app.cameraVersion);
  await page.waitForFunction(() => document.querySelector('#frame').dataset.final === 'true', null, { timeout: 20000 });
  await waitFinal(page, { cameraVersion: version });
  const camera = await page.evaluate(() => JSON.stringify(window.peakcast.app.camera));
  const before_ = await canvasSummary(page);
  await own.stop();
  await page.waitForFunction(() => document.body.dataset.status === 'disconnected', null, { timeout: 20000 });
  assert.match(await page.textContent('#status'), /disconnected/);
  await screenshot(page, 'disconnected');
  const again = await startServer([], own.port);
  try {
    const n = await frameCount(page);
    await waitFinal(page, { afterFrames: n, timeout: 40000 });
    assert.equal(await page.evaluate(() => JSON.stringify(window.peakcast.app.camera)), camera);
    const after_ = await canvasSummary(page);
    assert.ok(difference(before_, after_) < 2, `view changed after reconnect: ${difference(before_, after_)}`);
  } finally {
    await page.close();
    await again.stop();
  }
});

test('a wrong token shows the refusal', async () => {
  const guarded = await startServer(['--token', 'right']);
  try {
    const page = await openClient(browser, guarded.url + '/?token=wrong');
    await page.waitForFunction(() => document.body.dataset.status === 'refused', null, { timeout: 20000 });
    assert.match(await page.textContent('#status'), /refused/);
    assert.ok(await page.isVisible('#token-form'));
    await screenshot(page, 'refused');
    await page.fill('#token-input', 'right');
    await page.click('#token-form button');
    await waitFinal(page);
    await page.close();
  } finally {
    await guarded.stop();
  }
});

test('a full server shows why the client cannot connect', async () => {
  const full = await startServer(['--max-sessions', '1']);
  try {
    const first = await openClient(browser, full.url);
    await waitFinal(first);
    const second = await openClient(browser, full.url);
    await second.waitForFunction(() => /server full/.test(document.querySelector('#status').textContent), null, { timeout: 20000 });
    await screenshot(second, 'server_full');
    await first.close();  // the slot frees: the waiting client gets in on its next retry
    await waitFinal(second, { timeout: 40000 });
    await second.close();
  } finally {
    await full.stop();
  }
});
