// The stream's codec in the Rendering panel: JPEG, or a video codec the server encodes and this
// browser decodes (VideoDecoder.isConfigSupported), with a bit-rate ceiling. Remembered in this
// browser; the stream asks for it again after every reconnect.
import { decodableCodecs } from './video-decoder.js';

const KEY = 'peakcast.codec';

export class CodecPicker {
  constructor({ select, kbps, stream, disposer }) {
    Object.assign(this, { select, kbpsInput: kbps, stream });
    disposer.listen(select, 'change', () => this.#apply());
    disposer.listen(kbps, 'change', () => this.#apply());
  }

  async welcome(capabilities, limits) {
    const codecs = await decodableCodecs(capabilities.codecs ?? ['jpeg']);
    const wanted = this.select.value || localStorage.getItem(KEY) || 'jpeg';
    this.select.replaceChildren(...codecs.map((c) => new Option(c === 'jpeg' ? 'JPEG' : c.toUpperCase(), c)));
    this.select.value = codecs.includes(wanted) ? wanted : 'jpeg';
    this.kbpsInput.max = String(limits?.max_kbps ?? 200000);
    if (!this.kbpsInput.value && limits?.max_kbps) this.kbpsInput.value = String(limits.max_kbps);
    this.kbpsInput.disabled = this.select.value === 'jpeg';
    if (this.select.value !== this.stream.codec) this.#apply();
    this.select.dataset.ready = 'true';
  }

  #apply() {
    const codec = this.select.value;
    const kbps = Number(this.kbpsInput.value) || null;
    this.kbpsInput.disabled = codec === 'jpeg';
    localStorage.setItem(KEY, codec);
    this.stream.setCodec(codec, kbps);
  }
}
