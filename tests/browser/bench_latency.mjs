// Benchmark (a command, not a test): input -> frame-displayed latency measured in the browser,
// p50/p95 for interactive and final frames, on blobs 256^3 at a 1024x1024 viewport.
//   node tests/browser/bench_latency.mjs [--seconds 20] [--size 1024] [--interactive-ms MS]
// --interactive-ms sets the session's quality.interactive_ms (0: a fixed interactive scale).
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync } from 'node:fs';
import path from 'node:path';
import { ARTIFACTS, launch, openClient, PEAKCAST, ROOT, startServer, waitFinal } from './harness.mjs';

const arg = (name, dflt) => { const i = process.argv.indexOf(name); return i > 0 ? +process.argv[i + 1] : dflt; };
const seconds = arg('--seconds', 20), size = arg('--size', 1024), budget = arg('--interactive-ms', undefined);
const dataDir = path.join(ROOT, 'build/bench-data');
mkdirSync(dataDir, { recursive: true });
const vol = path.join(dataDir, 'blobs_256x256x256.raw');
if (!existsSync(vol)) execFileSync(PEAKCAST, ['make-volume', 'blobs', '--dims', '256', '256', '256', '-o', vol]);

const server = await startServer(['--volume', vol, '--data', dataDir]);
const browser = await launch();
try {
  const page = await openClient(browser, `${server.url}/`, { width: size + 340, height: size });
  await page.waitForFunction(() => window.peakcast?.app.welcomed, null, { timeout: 30000 });
  await page.selectOption('#volume-select', 'blobs_256x256x256');
  await waitFinal(page, { timeout: 60000 });
  if (budget !== undefined) await page.evaluate((ms) => window.peakcast.stream.send({ type: 'quality', interactive_ms: ms }), budget);
  const box = await page.locator('#frame').boundingBox();
  const end = Date.now() + seconds * 1000;
  let bursts = 0;
  while (Date.now() < end) {  // 1 s of dragging, 0.6 s still: interactive frames, then a final one
    await page.mouse.move(box.x + size / 2, box.y + size / 2);
    await page.mouse.down();
    const t0 = Date.now();
    for (let i = 0; Date.now() - t0 < 1000; i++) {
      await page.mouse.move(box.x + size / 2 + 150 * Math.sin(i / 10), box.y + size / 2 + 40 * Math.cos(i / 13));
      await page.waitForTimeout(16);
    }
    await page.mouse.up();
    await page.waitForTimeout(600);
    bursts++;
  }
  await page.waitForTimeout(1000);
  const r = await page.evaluate(() => {
    const s = window.peakcast.stats;
    const pct = (v, p) => { v = [...v].sort((a, b) => a - b); return v[Math.min(v.length - 1, Math.round(p * (v.length - 1)))]; };
    const i = s.latencies('interactive'), f = s.latencies('final');
    // The slowest 5% of interactive frames, part by part (mean), against the median frame's parts.
    const parts = s.latencyParts('interactive').sort((a, b) => a.total - b.total);
    const mean = (rows) => Object.fromEntries(Object.keys(rows[0] ?? {}).map((k) => [k, rows.reduce((a, r) => a + r[k], 0) / rows.length]));
    const slow = parts.slice(Math.floor(parts.length * 0.95));
    const mid = parts.slice(Math.floor(parts.length * 0.4), Math.ceil(parts.length * 0.6));
    return { n_i: i.length, i50: pct(i, 0.5), i95: pct(i, 0.95), n_f: f.length, f50: pct(f, 0.5), f95: pct(f, 0.95),
      slow: slow.length ? mean(slow) : null, render50: pct(s.renderTimes('interactive'), 0.5),
      render95: pct(s.renderTimes('interactive'), 0.95), mid: mid.length ? mean(mid) : null,
      frame: `${s.last.frame.width}x${s.last.frame.height}`, bytes: s.last.stats?.bytes, variant: s.last.stats?.variant,
      spr: s.last.stats?.samples_per_ray };
  });
  console.log(`blobs 256^3, ${size}x${size} viewport, ${bursts} drag bursts in ${seconds} s (Debian chromium, headless), ` +
    `interactive_ms ${budget ?? 'default'}`);
  console.log(`interactive: n=${r.n_i}  p50 ${r.i50?.toFixed(0)} ms  p95 ${r.i95?.toFixed(0)} ms`);
  console.log(`final:       n=${r.n_f}  p50 ${r.f50?.toFixed(0)} ms  p95 ${r.f95?.toFixed(0)} ms (includes the 150 ms still delay)`);
  console.log('input = camera message sent by the page; frame = decoded and drawn on the canvas');
  const dims = (p) => p && ` (frames ${p.width.toFixed(0)}x${p.height.toFixed(0)} on average)`;
  const fmt = (p) => p && `total ${p.total.toFixed(0)} = server input->rendered ${p.server_render.toFixed(0)} + encode ${p.encode.toFixed(0)}` +
    ` + decode ${p.decode.toFixed(0)} + draw ${p.draw.toFixed(0)} + the rest (network, page queues) ${(p.total - p.server_render - p.encode - p.decode - p.draw).toFixed(0)} ms${dims(p)}`;
  console.log(`interactive render ms (server): p50 ${r.render50?.toFixed(0)} p95 ${r.render95?.toFixed(0)}, final frame ${r.frame}, ${r.variant}, ${r.spr?.toFixed(1)} samples/ray`);
  console.log(`interactive, median 20%: ${fmt(r.mid)}`);
  console.log(`interactive, slowest 5%: ${fmt(r.slow)}`);
  await page.screenshot({ path: path.join(ARTIFACTS, 'bench_blobs.png') });
} finally {
  await browser.close();
  await server.stop();
}
