// The ray texture as data (Raspe & Müller 2008): the stroke list the client owns and the texels it
// computes from it with the server's arithmetic (server/core/ray_texture.cpp): a disk weighted 1
// inside (1 - falloff) x radius and smoothstep to 0 at the radius; set / add / multiply; clamped
// to the channel's range; level L edits 2^L x 2^L blocks weighted at the block's centre. Texels
// are float32 like the server's; the arithmetic is in doubles, as there.
export const CHANNELS = ['step', 'termination', 'blend'];
export const DEFAULT_RANGES = { step: [0.125, 8], termination: [0, 1], blend: [-1, 1] };
export const DEFAULT_TERMINATION = 1 - 1 / 255;  // the scene's early_termination default

export function brushWeight(r, falloff) {
  if (r >= 1) return 0;
  const inner = 1 - falloff;
  if (r <= inner) return 1;
  const x = (r - inner) / falloff;
  return 1 - x * x * (3 - 2 * x);
}

// The values a stroke may carry (the server refuses others, naming the key).
export function valueRange(channel, mode, ranges = DEFAULT_RANGES) {
  const [lo, hi] = ranges[channel];
  if (mode === 'add') return [-(hi - lo), hi - lo];
  if (mode === 'multiply') return [1 / 64, 64];
  return [lo, hi];
}

export class RayTextureModel {
  constructor({ mapping = 'view', width = 256, height = 256, termination = DEFAULT_TERMINATION, ranges = DEFAULT_RANGES } = {}) {
    this.mapping = mapping;
    this.width = width;
    this.height = height;
    this.termination = Math.min(1, Math.max(0, termination));
    this.ranges = ranges;
    this.strokes = [];
    this.texels = new Float32Array(width * height * 3);
    this.rebuild();
  }

  // What render.ray_texture carries (the first `limit` strokes).
  spec(limit = Infinity) {
    return { mapping: this.mapping, size: [this.width, this.height], strokes: this.strokes.slice(0, limit) };
  }

  push(stroke) {
    this.strokes.push(stroke);
    this.apply(stroke);
  }

  pop() {
    const s = this.strokes.pop();
    this.rebuild();
    return s;
  }

  // Keeps the first n strokes (an undone drag): one rebuild, however many strokes go.
  truncate(n) {
    if (n >= this.strokes.length) return;
    this.strokes.length = Math.max(0, n);
    this.rebuild();
  }

  rebuild() {
    const t = this.texels;
    for (let i = 0; i < t.length; i += 3) { t[i] = 1; t[i + 1] = this.termination; t[i + 2] = 0; }
    for (const s of this.strokes) this.apply(s);
  }

  at(x, y, channel) { return this.texels[(y * this.width + x) * 3 + CHANNELS.indexOf(channel)]; }

  apply(s) {
    const block = 1 << Math.min(Math.max(s.level ?? 0, 0), 8);
    const W = this.width, H = this.height, side = Math.max(W, H);
    const [lo, hi] = this.ranges[s.channel];
    const c = CHANNELS.indexOf(s.channel), [u, v] = s.center, falloff = s.falloff ?? 0, mode = s.mode ?? 'set';
    const rx = s.radius * side;
    const bx0 = Math.max(0, Math.floor((u * W - rx) / block)), bx1 = Math.min(Math.floor((W + block - 1) / block), Math.floor((u * W + rx) / block) + 1);
    const by0 = Math.max(0, Math.floor((v * H - rx) / block)), by1 = Math.min(Math.floor((H + block - 1) / block), Math.floor((v * H + rx) / block) + 1);
    for (let by = by0; by < by1; by++) {
      for (let bx = bx0; bx < bx1; bx++) {
        const x0 = bx * block, y0 = by * block, x1 = Math.min(W, x0 + block), y1 = Math.min(H, y0 + block);
        const dx = (0.5 * (x0 + x1) - u * W) / side, dy = (0.5 * (y0 + y1) - v * H) / side;
        const w = brushWeight(Math.sqrt(dx * dx + dy * dy) / s.radius, falloff);
        if (w <= 0) continue;
        for (let y = y0; y < y1; y++) {
          for (let x = x0; x < x1; x++) {
            const i = (y * W + x) * 3 + c;
            let t = this.texels[i];
            if (mode === 'set') t += w * (s.value - t);
            else if (mode === 'add') t += w * s.value;
            else t *= Math.pow(s.value, w);
            this.texels[i] = Math.min(hi, Math.max(lo, t));  // stored as float32, like the server
          }
        }
      }
    }
  }
}
