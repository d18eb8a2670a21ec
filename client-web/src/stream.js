// The WebSocket stream (proto/messages.md): hello, newest-frame-only decoding with
// createImageBitmap (video frames: every one, in order, through WebCodecs), an ack per frame,
// reconnection that resumes the session state, and a status for the page (connecting, live,
// disconnected, refused).
import { parseFrame } from './protocol.js';
import { VideoFrames } from './video-decoder.js';

export class Stream extends EventTarget {
  #ws = null;
  #pending = null;      // newest undecoded frame
  #decoding = false;
  #closed = false;
  #retryMs = 500;
  #timer = 0;
  #shownId = 0;         // the newest frame handed on: an older one decoded late is not drawn over it
  #newestId = 0;        // the newest frame received: stats of an older one are not passed on
  #video;
  codec = 'jpeg';       // interactive frames: jpeg or a video codec (asked for after every welcome)
  kbps = null;          // the video bit-rate ceiling asked for (null: the server's)

  constructor({ url, helloFor }) {
    super();
    this.url = url;
    this.helloFor = helloFor;  // () => hello message (with the state to resume)
    this.#video = new VideoFrames({
      onPicture: ({ frame, picture }) => this.#show(frame, picture),
      ack: (id) => this.send({ type: 'ack', frame: id }),
      askKey: () => this.send({ type: 'keyframe' }),
      onError: (message) => this.#emit('error', { code: 'decode', message }),
    });
  }

  // Interactive frames as `codec` from now on (and after every reconnect).
  setCodec(codec, kbps = this.kbps) {
    this.codec = codec;
    this.kbps = kbps;
    this.send({ type: 'quality', codec, ...(kbps ? { kbps } : {}) });
  }

  connect() {
    this.#closed = false;
    this.#emit('status', { state: 'connecting' });
    const ws = new WebSocket(this.url);
    ws.binaryType = 'arraybuffer';
    this.#ws = ws;
    ws.onopen = () => {
      this.#retryMs = 500;
      this.#shownId = this.#newestId = 0;  // a new session counts its frames from 1
      this.#video.close();
      ws.send(JSON.stringify(this.helloFor()));
    };
    ws.onmessage = (ev) => (typeof ev.data === 'string' ? this.#onText(ev.data) : this.#onFrame(ev.data));
    ws.onclose = (ev) => this.#onClose(ev);
  }

  send(message) {
    if (this.#ws && this.#ws.readyState === WebSocket.OPEN) this.#ws.send(JSON.stringify(message));
  }

  get live() { return this.#ws?.readyState === WebSocket.OPEN; }

  dispose() {
    this.#closed = true;
    clearTimeout(this.#timer);
    if (this.#ws) { this.#ws.onclose = null; this.#ws.close(); }
    this.#pending = null;
    this.#video.close();
  }

  #emit(type, detail) { this.dispatchEvent(new CustomEvent(type, { detail })); }

  #onText(text) {
    const msg = JSON.parse(text);
    if (msg.type === 'welcome') {
      this.#emit('status', { state: 'live' });
      if (this.codec !== 'jpeg' && msg.capabilities?.codecs?.includes(this.codec)) this.setCodec(this.codec);
    }
    if (msg.type === 'error' && msg.code === 'unauthorized') this.refused = 'unauthorized';
    // The server sends no stats of a frame older than one it sent (docs/streaming.md); kept here
    // too, so a time readout never steps back.
    if (msg.type === 'stats' && msg.frame < this.#newestId) return;
    this.#emit(msg.type, msg);
  }

  #onFrame(buffer) {
    const frame = parseFrame(buffer);
    frame.receivedAt = performance.now();
    this.#newestId = Math.max(this.#newestId, frame.id);
    if (frame.video) return this.#video.push(frame, this.codec);
    // Newest id wins: a frame the server encoded late can arrive after a newer one.
    if (this.#pending && frame.id < this.#pending.id) return this.send({ type: 'ack', frame: frame.id });
    if (this.#pending) this.send({ type: 'ack', frame: this.#pending.id });  // superseded, never shown
    this.#pending = frame;
    if (!this.#decoding) this.#decodeNewest();
  }

  async #decodeNewest() {
    this.#decoding = true;
    while (this.#pending) {
      const frame = this.#pending;
      this.#pending = null;
      try {
        const blob = new Blob([frame.image], { type: frame.png ? 'image/png' : 'image/jpeg' });
        const bitmap = await createImageBitmap(blob);
        if (this.#closed) {  // disposed while decoding: nobody will draw or close it
          bitmap.close();
          break;
        }
        frame.decodedAt = performance.now();
        this.#show(frame, bitmap);
      } catch (e) {
        this.#emit('error', { code: 'decode', message: String(e) });
      } finally {
        this.send({ type: 'ack', frame: frame.id });  // no-op once disposed
      }
    }
    this.#decoding = false;
  }

  // The listener owns and closes the picture (an ImageBitmap or a VideoFrame).
  #show(frame, picture) {
    if (frame.id < this.#shownId) return picture.close();
    this.#shownId = frame.id;
    this.#emit('frame', { frame, bitmap: picture });
  }

  #onClose(ev) {
    this.#ws = null;
    if (this.#closed) return;
    if (this.refused) {
      this.#emit('status', { state: 'refused', reason: this.refused });
      return;
    }
    const reason = ev.code === 1013 || ev.code === 1006 ? 'server unreachable' : (ev.reason || `closed (${ev.code})`);
    this.#emit('status', { state: 'disconnected', reason, retryMs: this.#retryMs });
    this.#timer = setTimeout(() => this.connect(), this.#retryMs);
    this.#retryMs = Math.min(this.#retryMs * 2, 5000);
  }
}
