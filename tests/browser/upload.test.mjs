// A volume file dropped on the view is uploaded (POST /api/volumes), opened, and stays in the
// volume menu; a file the server cannot read shows its reason.
import assert from 'node:assert/strict';
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
  await page.close();
});
