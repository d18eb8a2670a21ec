// A volume file dropped on the view is uploaded (POST /api/volumes), opened, and stays in the
// volume menu; a file the server cannot read shows its reason.
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { ROOT, frameCount, launch, openClient, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser, uploads;
before(async () => {
  uploads = mkdtempSync(path.join(os.tmpdir(), 'peakcast-uploads-'));
  server = await startServer(['--upload-dir', uploads]);
  browser = await launch();
});
after(async () => {
  await browser?.close();
  await server?.stop();
  rmSync(uploads, { recursive: true, force: true });
});

// Drops a file with these bytes on the view, as a user's drag from the desktop would.
async function drop(page, name, bytes) {
  await page.evaluate(async ({ name, b64 }) => {
    const bin = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
    const dt = new DataTransfer();
    dt.items.add(new File([bin], name));
    const view = document.querySelector('#view');
    for (const type of ['dragenter', 'dragover', 'drop'])
      view.dispatchEvent(new DragEvent(type, { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, { name, b64: Buffer.from(bytes).toString('base64') });
}

test('a dropped NRRD is uploaded, opened and kept in the volume menu', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const first = await page.evaluate(() => window.peakcast.app.volumeInfo.id);
  const n = await frameCount(page);
  await drop(page, 'my heptane.nrrd', readFileSync(path.join(ROOT, 'tests/data/heptane_151.nrrd')));
  await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id !== id, first, { timeout: 30000 });
  await waitFinal(page, { afterFrames: n });
  const info = await page.evaluate(() => window.peakcast.app.volumeInfo);
  assert.ok(info.uploaded && info.name === 'my heptane.nrrd' && info.id.startsWith('upload-'), JSON.stringify(info));
  assert.match(await page.title(), /upload-|my heptane/);
  const options = await page.$$eval('#volume-select option', (o) => o.map((x) => x.textContent));
  assert.ok(options.some((t) => t.startsWith('my heptane.nrrd (uploaded')), options.join(' | '));
  await screenshot(page, 'uploaded');
  // Back to the first volume: the upload stays in the menu, and can be opened again.
  await page.selectOption('#volume-select', first);
  await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id === id, first, { timeout: 30000 });
  const again = await page.$$eval('#volume-select option', (o) => o.map((x) => x.value));
  assert.ok(again.includes(info.id), again.join(' | '));
  assert.equal(await page.isVisible('#volume-delete'), false, 'a volume of the data directories has no delete');
  // Deleted from the viewer: the server lets it go, the viewer moves off it, the menu forgets it.
  await page.selectOption('#volume-select', info.id);
  await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id === id, info.id, { timeout: 30000 });
  assert.ok(await page.isVisible('#volume-delete'));
  await page.click('#volume-delete');
  await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id !== id, info.id, { timeout: 30000 });
  await page.waitForFunction((id) => ![...document.querySelectorAll('#volume-select option')].some((o) => o.value === id),
    info.id, { timeout: 10000 });
  const listed = await (await fetch(`${server.url}/api/volumes`)).json();
  assert.ok(!listed.volumes.some((v) => v.id === info.id), 'still on the server');
  assert.equal(await page.isVisible('#volume-delete'), false);
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('a file the server cannot read shows why, and nothing is opened', async () => {
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  const first = await page.evaluate(() => window.peakcast.app.volumeInfo.id);
  await drop(page, 'notes.txt', Buffer.from('not a volume at all\n'.repeat(20)));
  await page.waitForFunction(() => /⚠ notes.txt/.test(document.querySelector('#volume-progress').textContent), null,
    { timeout: 20000 });
  assert.match(await page.textContent('#volume-progress'), /neither NRRD/);
  assert.equal(await page.evaluate(() => window.peakcast.app.volumeInfo.id), first);
  // The refusal is shown, and nothing is left unhandled (an uncaught rejection before).
  await page.waitForTimeout(200);
  assert.deepEqual(page.errors, []);
  await page.close();
});

// A 24³ ball whose NRRD says its spacing is 500 nm: every length the viewer shows says so.
function ballNrrd() {
  const n = 24, voxels = Buffer.alloc(n ** 3);
  for (let z = 0; z < n; z++)
    for (let y = 0; y < n; y++)
      for (let x = 0; x < n; x++) voxels[(z * n + y) * n + x] = Math.hypot(x - 11.5, y - 11.5, z - 11.5) < 8 ? 200 : 10;
  const header = `NRRD0004\ntype: uint8\ndimension: 3\nsizes: ${n} ${n} ${n}\nspacings: 500 500 500\n` +
    'units: "nm" "nm" "nm"\nencoding: raw\n\n';
  return Buffer.concat([Buffer.from(header), voxels]);
}

test('lengths show in the volume\'s unit: scale bar, probe, measure, crop box, step and volume info', async () => {
  const page = await openClient(browser, server.url);
  // Every text the annotations draw (the scale bar's label is drawn on the overlay canvas).
  await page.addInitScript(() => {
    window.__drawn = [];
    const fill = CanvasRenderingContext2D.prototype.fillText;
    CanvasRenderingContext2D.prototype.fillText = function (t, ...a) { window.__drawn.push(String(t)); return fill.call(this, t, ...a); };
  });
  await page.reload();
  await waitFinal(page);
  const first = await page.evaluate(() => window.peakcast.app.volumeInfo.id);
  assert.equal(await page.evaluate(() => window.peakcast.app.volumeInfo.units), 'units', 'heptane names no unit');
  assert.match(await page.textContent('#controls'), /step \(units\)/);
  const n = await frameCount(page);
  await drop(page, 'ball.nrrd', ballNrrd());
  await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id !== id, first, { timeout: 30000 });
  await waitFinal(page, { afterFrames: n });
  assert.equal(await page.evaluate(() => window.peakcast.app.volumeInfo.units), 'nm');
  assert.match(await page.textContent('#volume-info'), /spacing 500 500 500 nm/);
  assert.match(await page.textContent('#controls'), /step \(nm\)/);
  // The box is 11.5 µm wide: the scale bar moves to µm ("2 µm", "5 µm"), never "world units".
  await page.evaluate(() => { window.__drawn = []; window.peakcast.annotations.update({}); });
  await page.waitForFunction(() => window.__drawn.some((t) => /\(at the centre\)/.test(t)));
  const bar = await page.evaluate(() => window.__drawn.find((t) => /\(at the centre\)/.test(t)));
  assert.match(bar, /^(1|2|5|10) µm \(at the centre\)$/, bar);
  // The probe's position, in the volume's unit.
  const box = await page.locator('#frame').boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.waitForFunction(() => /^value .* at \(.*\) nm/.test(document.querySelector('#probe-readout').textContent));
  // The measure's distance.
  await page.click('#measure');
  await page.mouse.click(box.x + box.width * 0.47, box.y + box.height * 0.5);
  await page.waitForFunction(() => window.peakcast.probe.points.length === 1);
  await page.mouse.click(box.x + box.width * 0.53, box.y + box.height * 0.52);
  await page.waitForFunction(() => window.peakcast.probe.points.length === 2);
  const d = +(await page.getAttribute('#probe-readout', 'data-distance'));
  const shown = await page.textContent('#probe-readout');
  const want = d >= 1000 ? `distance ${+(d / 1000).toPrecision(4)} µm` : `distance ${+d.toPrecision(4)} nm`;
  assert.ok(shown.includes(want), `${shown} (want ${want})`);
  await page.click('#measure');
  // The crop box's readout.
  await page.check('#clip-box');
  await page.waitForFunction(() => /^box x .* nm/.test(document.querySelector('#clip-readout').textContent));
  assert.deepEqual(page.errors, []);
  await screenshot(page, 'units');
  await page.close();
});

test('a dropped ZIP of a DICOM series opens as the series, in Hounsfield units', async () => {
  const dir = mkdtempSync(path.join(os.tmpdir(), 'peakcast-dicom-zip-'));
  const made = spawnSync('/usr/bin/python3', ['-c', `
import sys, os, zipfile, numpy as np
sys.path.insert(0, ${JSON.stringify(path.join(ROOT, 'tests/unit'))})
from dicom_fixtures import write_series
d = sys.argv[1]
k, j, i = np.meshgrid(np.arange(5), np.arange(12), np.arange(10), indexing='ij')
write_series(os.path.join(d, 's'), (24 + 100 * k + j + i).astype(np.int16), positions=[(0, 0, 1.5 * z) for z in range(5)],
             series_uid='1.2.3.8.1', description='Head', intercept=-1024, spacing=(0.5, 0.5))
with zipfile.ZipFile(os.path.join(d, 'head.zip'), 'w', zipfile.ZIP_DEFLATED) as z:
    for f in sorted(os.listdir(os.path.join(d, 's'))):
        z.write(os.path.join(d, 's', f), 'series/' + f)
`, dir]);
  assert.equal(made.status, 0, String(made.stderr));
  try {
    const page = await openClient(browser, server.url);
    await waitFinal(page);
    const first = await page.evaluate(() => window.peakcast.app.volumeInfo.id);
    await drop(page, 'head.zip', readFileSync(path.join(dir, 'head.zip')));
    await page.waitForFunction((id) => window.peakcast.app.volumeInfo?.id !== id, first, { timeout: 30000 });
    const info = await page.evaluate(() => window.peakcast.app.volumeInfo);
    assert.ok(info.uploaded && info.name === 'head.zip', JSON.stringify(info));
    assert.deepEqual([info.dims, info.spacing, info.range, info.value_unit, info.modality, info.dtype],
      [[10, 12, 5], [0.5, 0.5, 1.5], [-1000, -580], 'HU', 'CT', 'int16']);
    await waitFinal(page);
    assert.deepEqual(page.errors, []);
    await page.close();
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});
