// A video session's frames through WebCodecs (docs/streaming.md): every frame decoded in order
// (each refers to the one before), a key frame asked for after a loss or a decoder error, and
// each VideoFrame handed on to be drawn and closed. Frames are acked once decoded.

// WebCodecs codec strings for what the server sends: H.264 High (x264's, Annex B with in-band
// parameter sets), VP9 profile 0, AV1 main 8-bit.
export const CODEC_STRINGS = { h264: 'avc1.640028', vp9: 'vp09.00.10.08', av1: 'av01.0.04M.08' };

// The codecs of `offered` (the welcome's capabilities.codecs) this browser can decode: jpeg always.
export async function decodableCodecs(offered) {
  const out = ['jpeg'];
  if (typeof VideoDecoder === 'undefined') return out;
  for (const c of offered) {
    if (!CODEC_STRINGS[c]) continue;
    try {
      const { supported } = await VideoDecoder.isConfigSupported({ codec: CODEC_STRINGS[c], optimizeForLatency: true });
      if (supported) out.push(c);
    } catch { /* not this one */ }
  }
  return out;
}

export class VideoFrames {
  #decoder = null;
  #codec = '';
  #size = '';
  #needKey = true;
  #keyAsked = false;  // a key frame asked for and not yet come
  #headers = new Map();  // timestamp (frame id) -> header, until its picture comes out

  // onPicture({frame, picture}): the listener draws and closes the picture. ack(id), askKey().
  constructor({ onPicture, ack, askKey, onError }) {
    Object.assign(this, { onPicture, ack, askKey, onError });
  }

  get pending() { return this.#headers.size; }

  // A frame of a video session; `codec` is the session's (the server codes every video frame of
  // a session with the codec it asked for).
  push(frame, codec) {
    const size = `${frame.width}x${frame.height}`;
    if (frame.key && (codec !== this.#codec || size !== this.#size || !this.#decoder)) this.#open(codec, size);
    if (this.#needKey && !frame.key) {  // a delta frame without its reference: skipped, a key frame asked for (once)
      this.ack(frame.id);
      if (!this.#keyAsked) {
        this.#keyAsked = true;
        this.askKey();
      }
      return;
    }
    this.#needKey = this.#keyAsked = false;
    frame.decodeStart = performance.now();
    this.#headers.set(frame.id, frame);
    try {
      this.#decoder.decode(new EncodedVideoChunk({ type: frame.key ? 'key' : 'delta', timestamp: frame.id, data: frame.image }));
    } catch (e) {
      this.#failed(e);
    }
  }

  #open(codec, size) {
    this.#ackPending();  // the old decoder's frames still inside it will not come out: acked, or the server would wait for them
    this.close();
    this.#codec = codec;
    this.#size = size;
    this.#decoder = new VideoDecoder({
      output: (picture) => {
        const frame = this.#headers.get(picture.timestamp);
        this.#headers.delete(picture.timestamp);
        if (!frame) return picture.close();
        frame.decodedAt = performance.now();
        frame.decodeMs = frame.decodedAt - frame.decodeStart;
        this.ack(frame.id);
        this.onPicture({ frame, picture });
      },
      error: (e) => this.#failed(e),
    });
    this.#decoder.configure({ codec: CODEC_STRINGS[codec], optimizeForLatency: true });
  }

  #failed(e) {
    this.onError?.(String(e?.message ?? e));
    this.#ackPending();
    this.close();
    this.#keyAsked = true;
    this.askKey();
  }

  #ackPending() {
    for (const id of this.#headers.keys()) this.ack(id);
    this.#headers.clear();
  }

  // Also on a new connection: frames of the old session are forgotten, not acked.
  close() {
    if (this.#decoder && this.#decoder.state !== 'closed') this.#decoder.close();
    this.#headers.clear();
    this.#decoder = null;
    this.#codec = this.#size = '';
    this.#needKey = true;
    this.#keyAsked = false;
  }
}
