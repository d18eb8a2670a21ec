// Video streams in Debian's Chromium (docs/streaming.md): H.264 and VP9 decoded by WebCodecs
// match the lossless render, an orbit keeps up, a reconnect and a resize start again at a key
// frame, every VideoFrame is closed, a delta frame without its key frame is skipped and a key frame
// asked for, and a codec the server does not encode is refused by name.
import assert from 'node:assert/strict';
import { after, before, test } from 'node:test';
import { launch, screenshot, startServer, waitFinal } from './harness.mjs';

let server, browser;
before(async () => { server = await startServer(['--max-kbps', '20000']); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

// Before the page's scripts: keep every WebSocket, count the VideoFrames decoded and closed, and
// after each frame is drawn keep the canvas of the newest video frame.
function instrument(page) {
  return page.addInitScript(() => {
    window.__sockets = [];
    const WS = window.WebSocket;
    window.WebSocket = class extends WS {
      constructor(...a) { super(...a); window.__sockets.push(this); }
      send(m) { if (typeof m === 'string' && JSON.parse(m).type === 'keyframe') window.__video.asked++; return super.send(m); }
    };
    window.__video = { decoded: 0, closed: 0, shown: [], chunks: [], asked: 0, stats: [] };
    const close = VideoFrame.prototype.close;
    VideoFrame.prototype.close = function () { if (!this.__closed) { this.__closed = true; window.__video.closed++; } return close.call(this); };
    const Decoder = window.VideoDecoder;
    // Every chunk given to a decoder, in order: what a stream opens with, whether or not its
    // picture is drawn (a newer frame, such as a JPEG final, may already be on screen).
    const decode = Decoder.prototype.decode;
    Decoder.prototype.decode = function (chunk) { window.__video.chunks.push({ id: chunk.timestamp, type: chunk.type }); return decode.call(this, chunk); };
    window.VideoDecoder = class extends Decoder {
      constructor(init) { super({ ...init, output: (f) => { window.__video.decoded++; init.output(f); } }); }
    };
  });
}

async function open(view = { width: 1100, height: 640 }) {
  const page = await browser.newPage({ viewport: view });
  page.errors = [];
  page.on('pageerror', (e) => page.errors.push(e.message));
  await instrument(page);
  await page.goto(server.url);
  await waitFinal(page);
  // After the client's own listener has drawn a frame: note it, and keep the newest video frame's pixels.
  // Each frame's stats (codec, warnings): why a frame was not video, when one is not.
  await page.evaluate(() => window.peakcast.stream.addEventListener('stats', (e) => {
    const s = e.detail;
    window.__video.stats.push({ id: s.frame, final: s.final, codec: s.codec, warnings: s.warnings });
  }));
  await page.evaluate(() => window.peakcast.stream.addEventListener('frame', (e) => {
    const f = e.detail.frame;
    window.__video.shown.push({ id: f.id, video: f.video, key: f.key, final: f.final, camera: f.cameraVersion });
    if (f.video) {
      const c = document.querySelector('#frame');
      window.__video.last = c.getContext('2d').getImageData(0, 0, c.width, c.height);
    }
  }));
  return page;
}

// Resolves once a final frame is shown after `action` (a setting the server answers with a still).
async function settled(page, action) {
  const n = await page.evaluate(() => window.__video.shown.length);
  await action();
  await page.waitForFunction((k) => window.__video.shown.slice(k).some((f) => f.final), n, { timeout: 30000 });
}

async function useCodec(page, codec) {
  await page.waitForFunction(() => document.querySelector('#codec').dataset.ready === 'true');
  await settled(page, () => page.selectOption('#codec', codec));
}

// A mouse orbit of `steps` moves; resolves with the frames shown meanwhile, the seconds it took,
// and the orbit's interactive frames: those of its cameras. A frame shown meanwhile may be one
// rendered before the orbit, for a setting sent earlier (on a busy machine, the interactive frame
// of a render change sent before the codec was), and says nothing of the orbit's frames.
async function orbit(page, steps = 30, dx = 10) {
  const box = await page.locator('#frame').boundingBox();
  const [n0, camera0] = await page.evaluate(() => [window.__video.shown.length, window.peakcast.app.cameraVersion]);
  const t0 = Date.now();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= steps; i++) {
    await page.mouse.move(box.x + box.width / 2 + i * dx, box.y + box.height / 2 + i * 2);
    await page.waitForTimeout(33);
  }
  await page.mouse.up();
  const seconds = (Date.now() - t0) / 1000;
  const shown = await page.evaluate((n) => window.__video.shown.slice(n), n0);
  return { shown, seconds, interactive: shown.filter((f) => !f.final && f.camera > camera0) };
}

// Resolves once the final frame of the orbit's last camera is shown. A final frame alone is not
// enough: on a busy machine the client may still hold a move back (frames in flight) while the
// server, quiet meanwhile, sends a still of an earlier camera, and the held move's video frame
// then comes after it.
async function orbitSettled(page) {
  const version = await page.evaluate(() => window.peakcast.app.cameraVersion);
  await waitFinal(page, { cameraVersion: version });
}

// PSNR (dB) of the last video frame drawn against the canvas now (the lossless final frame).
const psnrLastVideoAgainstCanvas = (page) => page.evaluate(() => {
  const c = document.querySelector('#frame');
  const a = window.__video.last.data, b = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let se = 0, n = 0;
  for (let i = 0; i < a.length; i += 4) for (let k = 0; k < 3; k++) { se += (a[i + k] - b[i + k]) ** 2; n++; }
  return 10 * Math.log10(255 * 255 / (se / n));
});

test('this Chromium decodes H.264 and VP9, and the panel offers them', async () => {
  const page = await open();
  await page.waitForFunction(() => document.querySelector('#codec').dataset.ready === 'true');
  const offered = await page.$$eval('#codec option', (o) => o.map((x) => x.value));
  assert.ok(offered.includes('h264') && offered.includes('vp9'), `offered: ${offered}`);
  assert.equal(offered[0], 'jpeg');
  await page.close();
});

for (const codec of ['h264', 'vp9']) {
  test(`${codec}: interactive frames are video, match the lossless render, and every VideoFrame is closed`, async () => {
    const page = await open();
    // Full-size interactive frames with differential sampling (s_k counts pixels, so an
    // interactive frame renders exactly what the final frame does) and a lossless final frame:
    // the last video frame and the final frame show the same pixels but for the codec's loss.
    await page.evaluate(() => {
      window.peakcast.stream.send({ type: 'quality', interactive_scale: 1, interactive_ms: 0, final_format: 'png' });
      window.peakcast.stream.send({ type: 'render', render: { sampling: 'differential' } });
    });
    await useCodec(page, codec);
    const run = await orbit(page, 20);
    assert.ok(run.interactive.length >= 3, `only ${run.interactive.length} interactive frames`);
    const statsOf = () => page.evaluate(() => window.__video.stats);
    assert.ok(run.interactive.every((f) => f.video), JSON.stringify({ shown: run.interactive, stats: await statsOf() }));
    const version = await page.evaluate(() => window.peakcast.app.cameraVersion);
    await waitFinal(page, { cameraVersion: version });
    const stats = await page.textContent('#stats');
    assert.match(stats, /png|jpeg/);  // the final frame is a still
    // The last video frame shows the camera the final frame does when the orbit ended on it.
    const db = await psnrLastVideoAgainstCanvas(page);
    console.log(`${codec}: last video frame vs the lossless final frame: ${db.toFixed(1)} dB`);
    assert.ok(db > 30, `${codec}: ${db.toFixed(1)} dB`);
    const v = await page.evaluate(() => window.__video);
    assert.ok(v.decoded >= run.interactive.length, JSON.stringify(v));
    assert.equal(v.closed, v.decoded, 'a VideoFrame was not closed');
    assert.deepEqual(page.errors, []);
    await screenshot(page, `video-${codec}`);
    await page.close();
  });
}

test('a video orbit keeps up with a JPEG one', async () => {
  const page = await open();
  const fps = (r) => r.interactive.length / r.seconds;
  // A round is a JPEG orbit and an H.264 orbit back to back; a round's ratio compares the two
  // under the same load. Under CTest the machine is shared with other tests, whose load comes
  // and goes: the best of up to three rounds counts (each codec's best over different rounds
  // compared a quiet JPEG round with a busy H.264 one: 13.1 against 7.0 frames/s, while the
  // busy round's own pair was 8.0 against 7.0). A further round only when the last falls short.
  const rounds = [];
  let best = 0;
  for (let round = 0; round < 3 && best < 0.7; round++) {
    const r = {};
    for (const codec of ['jpeg', 'h264']) {
      if (round > 0 || codec !== 'jpeg') await useCodec(page, codec);
      const run = await orbit(page, 40, codec === 'jpeg' ? 10 : -10);
      if (codec === 'h264') assert.ok(run.interactive.every((f) => f.video), JSON.stringify(run.interactive));
      r[codec] = fps(run);
      console.log(`orbit round ${round + 1}: ${codec} ${r[codec].toFixed(1)} frames/s`);
      await orbitSettled(page);
    }
    rounds.push(r);
    best = Math.max(best, r.h264 / r.jpeg);
  }
  assert.ok(best >= 0.7, `h264 against jpeg frames/s, by round: ${rounds.map((r) => `${r.h264.toFixed(1)}/${r.jpeg.toFixed(1)}`).join(', ')}`);
  const pending = await page.evaluate(() => window.__video.decoded - window.__video.closed);
  assert.equal(pending, 0);
  await page.close();
});

test('a reconnect and a resize start again at a key frame', async () => {
  const page = await open();
  await useCodec(page, 'vp9');
  const first = await orbit(page, 10);
  assert.ok(first.interactive[0].video && first.interactive[0].key, JSON.stringify(first.interactive[0]));
  await orbitSettled(page);
  // The connection drops: the client reconnects, asks for vp9 again, and the new stream opens with a key frame.
  // After `action` and an orbit: the chunks decoded, and the video frames shown. The stream is
  // judged by what reached the decoder: its first picture may be one the client rightly does not
  // draw (when the codec is asked for before the server renders the new session's first frame,
  // that frame is the key frame, and the JPEG final after it may be drawn first).
  const videoAfter = async (action) => {
    const [n, m, a] = await page.evaluate(() => [window.__video.shown.length, window.__video.chunks.length, window.__video.asked]);
    await settled(page, action);
    await orbit(page, 10, -10);
    await orbitSettled(page);
    return page.evaluate(([k, c, q]) => ({ chunks: window.__video.chunks.slice(c), shown: window.__video.shown.slice(k).filter((f) => f.video),
      asked: window.__video.asked - q }), [n, m, a]);
  };
  // A stream that opened with a delta frame would be skipped by the client until it asked for a
  // key frame: so no key frame may have been asked for.
  const opensWithKey = (after, what) => {
    const { chunks, shown, asked } = after;
    const seen = JSON.stringify(after);
    assert.equal(asked, 0, `a key frame was asked for after the ${what}: ${seen}`);
    assert.ok(chunks.length > 1 && chunks[0].type === 'key', `no key frame after the ${what}: ${seen}`);
    assert.ok(chunks.slice(1).every((c) => c.type === 'delta'), `a second key frame after the ${what}: ${seen}`);
    assert.ok(shown.length > 1 && shown.every((f) => f.id >= chunks[0].id), `video not shown after the ${what}: ${seen}`);
  };
  opensWithKey(await videoAfter(() => page.evaluate(() => window.__sockets.at(-1).close())), 'reconnect');
  assert.equal(await page.evaluate(() => window.__sockets.length), 2);
  opensWithKey(await videoAfter(() => page.setViewportSize({ width: 1200, height: 560 })), 'resize');
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('delta frames without their key frame are skipped and acked, and one key frame is asked for', async () => {
  const page = await browser.newPage();
  await page.goto(server.url);
  const got = await page.evaluate(async () => {
    const { VideoFrames } = await import('./src/video-decoder.js');
    const acks = [], asks = [], pictures = [];
    const frames = new VideoFrames({ onPicture: ({ frame, picture }) => { pictures.push(frame.id); picture.close(); },
      ack: (id) => acks.push(id), askKey: () => asks.push(acks.length), onError: () => {} });
    const delta = (id) => ({ id, key: false, width: 64, height: 64, image: new Uint8Array(8) });
    for (const id of [1, 2, 3]) frames.push(delta(id), 'vp9');
    const before = { acks: [...acks], asks: [...asks], pending: frames.pending };
    frames.close();  // a new connection: the next gap asks again
    frames.push(delta(4), 'vp9');
    return { before, acks, asks, pictures };
  });
  assert.deepEqual(got.before, { acks: [1, 2, 3], asks: [1], pending: 0 });
  assert.deepEqual(got.asks, [1, 4]);
  assert.deepEqual(got.pictures, []);
  await page.close();
});

test('a codec the server does not encode is refused by name', async () => {
  const page = await open();
  await page.evaluate(() => window.peakcast.stream.setCodec('mpeg2'));
  await page.waitForFunction(() => !document.querySelector('#error').hidden);
  assert.match(await page.textContent('#error'), /'mpeg2' is not a codec this server encodes \(jpeg, h264, vp9/);
  await page.close();
});
