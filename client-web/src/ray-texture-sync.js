// Keeps the server's ray texture equal to the client's stroke list (proto/messages.md): strokes
// are edits, never dropped. The list is the truth; the server has been sent its first `sent`
// strokes and is known to hold its first `confirmed`.
//   replace  render.ray_texture with the first HELLO_LIMIT strokes (a render message is at most
//            256 KiB), a ping whose pong confirms them, the rest as stroke messages;
//   stroke   {seq: index in the list, 1-based}, answered by stroke_ack {seq, strokes};
//   hello    after a reconnect the hello's state carries the first HELLO_LIMIT strokes and the
//            rest follow once the welcome is in.
// Sending is paced below the server's message rate (a burst of 500, then 250/s, shared with the
// frame acks) and windowed by acks (the server closes a client that leaves 64 answers unread):
// strokes wait here, in order, until they may go.
export const HELLO_LIMIT = 1000;
const RATE = 150, BURST = 100, WINDOW = 32;  // strokes per second, bucket size, un-acked strokes

export class RayTextureSync extends EventTarget {
  model = null;       // RayTextureModel, or null: no texture in the session
  sent = 0;
  confirmed = 0;
  failed = '';        // the server refused the texture (a reason), until the next replace
  helloLimit = HELLO_LIMIT;
  #ready = false;     // welcomed: stroke messages may go
  #epoch = 0;         // bumped by every replace and hello; older acks only pop their entry
  #inflight = [];     // {seq, epoch} of stroke messages not yet answered, in send order
  #pong = null;       // {id, epoch, carried}: a replace waiting for its ping's answer
  #unsent = false;    // a replace made while the socket could not take it (between hello and welcome)
  #tokens = BURST;
  #refilled = performance.now();
  #timer = 0;

  constructor(stream) { super(); this.stream = stream; }

  get pending() { return this.model ? this.model.strokes.length - this.confirmed : 0; }
  get queued() { return this.model ? this.model.strokes.length - this.sent : 0; }
  get inflight() { return this.#inflight.length; }

  // The hello's render.ray_texture (a new connection: what the old one had in flight is gone).
  helloSpec() {
    this.#reset();
    this.#inflight = [];
    this.#ready = false;
    this.#unsent = false;  // the hello carries the newest list
    if (!this.model) return null;
    this.sent = Math.min(this.helloLimit, this.model.strokes.length);
    this.#pong = { epoch: this.#epoch, carried: this.sent, id: null };  // the welcome confirms these
    return this.model.spec(this.helloLimit);
  }

  // The welcome's state.render.ray_texture: the hello's texture, now in the session. Should the
  // session hold something else, it gets ours whole.
  welcome(serverSpec) {
    this.#ready = true;
    const hello = this.#pong?.id === null && this.#pong.epoch === this.#epoch ? this.#pong : null;
    if (hello) this.#pong = null;
    const m = this.model;
    if (this.#unsent || (m && (!serverSpec || serverSpec.mapping !== m.mapping || (hello && serverSpec.strokes?.length !== hello.carried)))) return this.replace(m);
    if (m && hello) this.confirmed = Math.max(this.confirmed, hello.carried);
    this.#pump();
  }

  // A texture the session already holds whole.
  adopt(model) {
    this.model = model;
    this.#reset();
    this.#unsent = false;
    this.sent = this.confirmed = model.strokes.length;
  }

  // The page drops its texture without telling the server (one that takes no ray textures).
  forget() {
    this.model = null;
    this.#reset();
    this.#unsent = false;
  }

  disconnected() { this.#ready = false; }

  // Sends the model whole (after undo, clear, a mapping switch), or removes the texture (null).
  replace(model) {
    this.model = model;
    this.#reset();
    this.#unsent = false;
    if (this.stream.live && this.#ready) {
      const spec = model ? model.spec(this.helloLimit) : null;
      this.stream.send({ type: 'render', render: { ray_texture: spec } });
      this.sent = spec ? spec.strokes.length : 0;
      this.#pong = { epoch: this.#epoch, carried: this.sent, id: `ray-texture-${this.#epoch}` };
      this.stream.send({ type: 'ping', id: this.#pong.id });
    } else this.#unsent = true;
    this.#pump();
  }

  added() { this.#pump(); }

  onAck(msg) {
    const head = this.#inflight.shift();
    if (head && head.epoch === this.#epoch) {
      if (msg.seq === head.seq && msg.strokes === head.seq) this.confirmed = Math.max(this.confirmed, head.seq);
      else return this.replace(this.model);  // the server's list is not ours: send ours whole
    }
    this.#pump();
  }

  onPong(msg) {
    if (!this.#pong || msg.id !== this.#pong.id) return;
    if (this.#pong.epoch === this.#epoch && !this.failed) this.confirmed = Math.max(this.confirmed, this.#pong.carried);
    this.#pong = null;
    this.#changed();
  }

  // An error the server answered: the texture of a replace, or a stroke, was refused.
  onError(msg) {
    const text = String(msg.message ?? '');
    if (this.#pong && /ray_texture/.test(text) && !/^stroke/.test(text)) {
      this.failed = text;
      this.#changed();
    } else if (this.#inflight.length && /stroke/.test(text)) {
      const head = this.#inflight.shift();
      if (head.epoch === this.#epoch && !this.failed) this.replace(this.model);  // e.g. the session lost its texture
    }
  }

  dispose() { clearTimeout(this.#timer); this.#timer = 0; }

  // Strokes already sent on this connection stay in #inflight: their answers still come.
  #reset() {
    this.#epoch++;
    this.#pong = null;
    this.sent = this.confirmed = 0;
    this.failed = '';
  }

  #pump() {
    clearTimeout(this.#timer);
    this.#timer = 0;
    const strokes = this.model?.strokes ?? [];
    const now = performance.now();
    this.#tokens = Math.min(BURST, this.#tokens + ((now - this.#refilled) * RATE) / 1000);
    this.#refilled = now;
    while (this.#ready && this.stream.live && !this.failed && this.sent < strokes.length && this.#inflight.length < WINDOW && this.#tokens >= 1) {
      const seq = this.sent + 1;
      this.stream.send({ type: 'stroke', seq, stroke: strokes[seq - 1] });
      this.#inflight.push({ seq, epoch: this.#epoch });
      this.sent = seq;
      this.#tokens -= 1;
    }
    if (this.#ready && this.sent < strokes.length && this.#inflight.length < WINDOW && !this.failed)  // paced: wait for a token
      this.#timer = setTimeout(() => this.#pump(), Math.ceil(((1 - this.#tokens) * 1000) / RATE) + 1);
    this.#changed();
  }

  #changed() { this.dispatchEvent(new Event('change')); }
}
