// Browser-test helpers: a real `peakcast serve` on loopback and Debian's chromium through
// playwright-core (executablePath /usr/bin/chromium; no browser is ever downloaded).
import { spawn } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = path.dirname(fileURLToPath(import.meta.url));
export const ROOT = path.resolve(here, '../..');
export const PEAKCAST = process.env.PEAKCAST_BIN || path.join(ROOT, 'build/server/peakcast');
export const ARTIFACTS = process.env.PEAKCAST_ARTIFACTS || path.join(ROOT, 'build/test-artifacts/browser');
mkdirSync(ARTIFACTS, { recursive: true });

export function startServer(args = [], port = 0) {
  const data = path.join(ROOT, 'tests/data');
  const proc = spawn(PEAKCAST, ['serve', '--port', String(port), '--data', data, '--volume', path.join(data, 'heptane_151.nrrd'), ...args],
    { stdio: ['ignore', 'pipe', 'pipe'] });
  return new Promise((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => reject(new Error('server did not start: ' + out)), 60000);
    proc.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/serving on http:\/\/([\d.]+):(\d+)/);
      if (m) {
        clearTimeout(timer);
        resolve({ proc, url: `http://${m[1]}:${m[2]}`, port: +m[2], stop: () => stop(proc) });
      }
    });
    proc.stderr.on('data', (d) => { out += d; });
    proc.on('exit', (code) => reject(new Error(`server exited ${code}: ${out}`)));
  });
}

function stop(proc) {
  return new Promise((resolve) => {
    if (proc.exitCode !== null) return resolve();
    proc.on('exit', resolve);
    proc.kill('SIGTERM');
  });
}

export async function launch() {
  return chromium.launch({
    executablePath: '/usr/bin/chromium',
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
}

// With `versions`, the page counts the render and stroke messages it sends after each welcome,
// so that waitFinal({ current: true }) can tell a frame of everything sent from an older one.
export async function openClient(browser, url, { width = 1200, height = 700, versions = false } = {}) {
  const page = await browser.newPage({ viewport: { width, height } });
  page.errors = [];
  page.on('pageerror', (e) => page.errors.push(e.message));
  if (versions) await page.addInitScript(countRenderMessages);
  await page.goto(url);
  return page;
}

// The render version the server is at once it has read everything sent: the last welcome's,
// +1 per render and stroke message sent after it (the server bumps it once per accepted one).
function countRenderMessages() {
  let base = 0, sent = 0;
  window.__renderVersion = () => base + sent;
  const WS = window.WebSocket;
  window.WebSocket = class extends WS {
    constructor(...a) {
      super(...a);
      this.addEventListener('message', (e) => {
        if (typeof e.data !== 'string') return;
        const m = JSON.parse(e.data);
        if (m.type === 'welcome') { base = m.state?.versions?.render ?? 0; sent = 0; }
      });
    }
    send(data) {
      if (typeof data === 'string' && ['render', 'stroke'].includes(JSON.parse(data).type)) sent++;
      super.send(data);
    }
  };
}

// Waits for a final frame showing at least `cameraVersion`, after `afterFrames` frames. With
// `currentTf`, the frame must also show the TF editor's newest version: several edits in a row
// may be slower than the still delay, and a final frame come between them. With `current` (a
// page opened with `versions`), the frame must show every render message sent so far: the final
// of an earlier setting can arrive after a later one is sent.
export async function waitFinal(page, { afterFrames = 0, cameraVersion = 0, currentTf = false, current = false, timeout = 30000 } = {}) {
  await page.waitForFunction(([n, v, tf, cur]) => {
    const c = document.querySelector('#frame');
    const tfShown = !tf || +(c.dataset.tfVersion || 0) >= window.peakcast.tfEditor.version;
    const renderShown = !cur || +(c.dataset.renderVersion || 0) >= window.__renderVersion();
    return c.dataset.final === 'true' && +(c.dataset.frames || 0) > n && +(c.dataset.cameraVersion || 0) >= v && tfShown && renderShown;
  }, [afterFrames, cameraVersion, currentTf, current], { timeout });
}

// Records every text `selector` shows from now on (a load's progress line comes and goes faster
// than a test can look); returns a function that reads the list.
export async function recordTexts(page, selector) {
  await page.evaluate((sel) => {
    const el = document.querySelector(sel);
    (window.__texts ??= {})[sel] = [];
    new MutationObserver(() => window.__texts[sel].push(el.textContent))
      .observe(el, { childList: true, characterData: true, subtree: true });
  }, selector);
  return () => page.evaluate((sel) => window.__texts[sel], selector);
}

export const frameCount = (page) => page.evaluate(() => +(document.querySelector('#frame').dataset.frames || 0));

// The editor's tests start from a known TF, a grey ramp over the volume's range (two points),
// whatever TF the server derived for the first picture: set as the user would, and its frame
// waited for.
export async function greyRamp(page) {
  const n = await frameCount(page);
  await page.evaluate(() => {
    const e = window.peakcast.tfEditor;
    e.set([[e.lo, 0, 0, 0, 0], [e.hi, 1, 1, 1, 1]], { silent: false });
  });
  await waitFinal(page, { afterFrames: n });
}

// Mean and spread of the canvas pixels, and a small grey thumbnail to compare images.
export function canvasSummary(page) {
  return page.evaluate(() => {
    const c = document.querySelector('#frame');
    const t = document.createElement('canvas');
    t.width = 64; t.height = 40;
    const g = t.getContext('2d');
    g.drawImage(c, 0, 0, 64, 40);
    const d = g.getImageData(0, 0, 64, 40).data;
    const grey = [];
    let sum = 0, lit = 0;
    for (let i = 0; i < d.length; i += 4) {
      const v = (d[i] + d[i + 1] + d[i + 2]) / 3;
      grey.push(v); sum += v; if (v > 20) lit++;
      grey.red = (grey.red || 0) + d[i];
    }
    return { mean: sum / grey.length, lit: lit / grey.length, grey, red: grey.red / grey.length };
  });
}

export function difference(a, b) {
  let s = 0;
  for (let i = 0; i < a.grey.length; i++) s += Math.abs(a.grey[i] - b.grey[i]);
  return s / a.grey.length;
}

export async function screenshot(page, name) {
  await page.screenshot({ path: path.join(ARTIFACTS, name + '.png') });
}
