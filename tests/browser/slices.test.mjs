// Slice views beside the 3D view (POST /api/slice in panes) and DICOM series in the data browser
// with the CT presets in Hounsfield units. Debian's chromium through playwright-core, against a
// real server.
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { ROOT, launch, openClient, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

test('a DICOM series: listed with its description, opened from the data browser, CT presets in HU only where the volume says so', async () => {
  const dir = mkdtempSync(path.join(os.tmpdir(), 'peakcast-dicom-'));
  // A CT series (HU -1000..1000 over z) and the same values as a raw int16 volume that names no unit.
  const made = spawnSync('/usr/bin/python3', ['-c', `
import sys, os, json, numpy as np
sys.path.insert(0, ${JSON.stringify(path.join(ROOT, 'tests/unit'))})
from dicom_fixtures import write_series
d = sys.argv[1]
k, j, i = np.meshgrid(np.arange(12), np.arange(16), np.arange(16), indexing='ij')
hu = (-1000 + (2000 * k) // 11 + 0 * (j + i)).astype(np.int16)
write_series(os.path.join(d, 'chest'), (hu + 1024).astype(np.int16), positions=[(0, 0, 2.0 * z) for z in range(12)],
             series_uid='1.2.3.7.1', description='Chest bone', intercept=-1024)
hu.tofile(os.path.join(d, 'plain.raw'))
json.dump({'dims': [16, 16, 12], 'dtype': 'int16'}, open(os.path.join(d, 'plain.raw.json'), 'w'))
`, dir]);
  assert.equal(made.status, 0, String(made.stderr));
  const s = await startServer(['--data', dir]);
  try {
    const page = await openClient(browser, s.url);
    await waitFinal(page);
    await page.click('#volume-browse');
    await page.waitForSelector('#files li button');
    const entries = await page.$$eval('#files li button', (b) => b.map((e) => [e.textContent, e.title]));
    const chest = entries.find(([t]) => t.includes('chest'));
    assert.ok(chest && chest[0].includes('Chest bone') && /DICOM CT series, 16×16×12/.test(chest[1]), JSON.stringify(entries));
    await page.click('#files button:has-text("chest")');
    await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'chest', null, { timeout: 30000 });
    assert.equal(await page.evaluate(() => window.peakcast.app.volumeInfo.value_unit), 'HU');
    await waitFinal(page);
    const points = () => page.evaluate(() => window.peakcast.tfEditor.points.map((p) => p[0]));
    await page.selectOption('#tf-preset', 'ct-bone');
    assert.deepEqual((await points()).slice(1, 4), [-100, 200, 300], 'ct-bone at its HU values');
    // The same values in a file that does not say HU: the preset spreads over the range.
    await page.fill('#volume-path', 'plain.raw');
    await page.press('#volume-path', 'Enter');
    await page.waitForFunction(() => window.peakcast.app.volumeInfo?.id === 'plain.raw', null, { timeout: 30000 });
    await waitFinal(page);
    assert.equal(await page.evaluate(() => window.peakcast.app.volumeInfo.value_unit), undefined);
    await page.selectOption('#tf-preset', 'ct-bone');
    assert.deepEqual((await points()).slice(1, 4), [-500, 0, 500], 'ct-bone spread over -1000..1000');
    assert.deepEqual(page.errors, []);
    await page.close();
  } finally {
    await s.stop();
    rmSync(dir, { recursive: true, force: true });
  }
});

test('slice views: three server slices through a point, moved by clicks, the wheel and a click in 3D', async () => {
  const page = await openClient(browser, server.url, { width: 1280, height: 800 });
  await waitFinal(page);
  assert.ok(await page.isHidden('#slices'), '3D only by default');
  const loads = () => page.$$eval('.slice-pane canvas', (c) => c.map((e) => +(e.dataset.loads || 0)));
  const indices = () => page.$$eval('.slice-pane canvas', (c) => c.map((e) => +e.dataset.index));
  await page.check('#layout-slices');
  await page.waitForFunction(() => [...document.querySelectorAll('.slice-pane canvas')].every((c) => +(c.dataset.loads || 0) >= 1));
  const info = await page.evaluate(() => window.peakcast.app.volumeInfo);
  assert.deepEqual(await indices(), info.dims.map((d) => Math.round((d - 1) / 2)), 'through the centre');
  // The z pane is the server's slice of the scene at its size (the crosshair aside).
  const differ = await page.evaluate(async () => {
    const { app, slices } = window.peakcast, c = document.querySelector('#slice-z');
    const body = { volume: app.volume, tf: { points: app.tf }, time: app.time, image: { width: c.width, height: c.height },
      slice: { axis: 'z', index: +c.dataset.index } };
    const res = await fetch('/api/slice', { method: 'POST', body: JSON.stringify(body) });
    const ref = new OffscreenCanvas(c.width, c.height).getContext('2d');
    ref.drawImage(await createImageBitmap(await res.blob()), 0, 0);
    const a = ref.getImageData(0, 0, c.width, c.height).data, b = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const [px, py] = slices.pixelOf(2);
    let n = 0;
    for (let y = 0; y < c.height; y++)
      for (let x = 0; x < c.width; x++) {
        if (Math.abs(x - px) < 2 || Math.abs(y - py) < 2) continue;
        const i = 4 * (y * c.width + x);
        n += Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]) > 3;
      }
    return n;
  });
  assert.equal(differ, 0, 'the pane shows POST /api/slice');
  // A click on the z slice moves the point there: the x and y slices are drawn again, z stays.
  const before = await loads(), box = await page.locator('#slice-z').boundingBox();
  await page.mouse.click(box.x + box.width * 0.3, box.y + box.height * 0.5);
  await page.waitForFunction((b) => {
    const l = [...document.querySelectorAll('.slice-pane canvas')].map((e) => +(e.dataset.loads || 0));
    return l[0] > b[0] && l[1] > b[1];
  }, before);
  const after = await indices();
  assert.equal(after[2], Math.round((info.dims[2] - 1) / 2), 'the z slice stays');
  assert.ok(after[0] < Math.round((info.dims[0] - 1) / 2), `clicked left of the centre: x ${after[0]}`);
  const at = await page.evaluate(() => window.peakcast.slices.pixelOf(2));
  const scale = await page.$eval('#slice-z', (c) => c.width / c.clientWidth);
  assert.ok(Math.abs(at[0] - box.width * 0.3 * scale) <= 2 * scale && Math.abs(at[1] - box.height * 0.5 * scale) <= 2 * scale, `crosshair at ${at}`);
  // The wheel steps the z slice by one voxel.
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.wheel(0, 100);
  await page.waitForFunction((z) => +document.querySelector('#slice-z').dataset.index === z + 1, after[2]);
  // A click in the 3D view moves the point to what it hit there.
  const moved = page.evaluate(() => new Promise((resolve) => window.peakcast.slices.addEventListener('point', (e) => resolve(e.detail), { once: true })));
  const view = await page.locator('#frame').boundingBox();
  await page.mouse.click(view.x + view.width / 2, view.y + view.height / 2);
  const hit = await moved;
  const box3 = [0, 1, 2].map((a) => [info.origin[a], info.origin[a] + (info.dims[a] - 1) * info.spacing[a]]);
  assert.ok(hit.every((v, a) => v >= box3[a][0] && v <= box3[a][1]), `the hit ${hit} lies in the box`);
  await screenshot(page, 'slices');
  assert.deepEqual(page.errors, []);
  await page.close();
});
