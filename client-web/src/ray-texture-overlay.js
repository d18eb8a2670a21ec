// What the brush draws over the image: the ray texture's selected channel as a small preview
// (computed by the client from its strokes, ray-texture-model.js) and the brush outline that
// follows the pointer, in image pixels.
import { volumeToImage } from './ray-texture-mapping.js';

const PREVIEW_SIDE = 128;

// Channel value -> RGB. termination: grey (black 0, white 1); step and blend: diverging about
// their default (step on a log2 scale: blue finer, orange coarser; blend: orange fades DVR,
// blue fades peaks).
function colour(channel, x) {
  if (channel === 'termination') { const g = Math.round(255 * x); return [g, g, g]; }
  const t = channel === 'step' ? Math.log2(x) / 3 : x;  // [-1, 1]
  const a = Math.min(1, Math.abs(t)), to = t < 0 ? [70, 160, 255] : [255, 150, 40];
  return to.map((c) => Math.round(48 + (c - 48) * a));
}

export const LEGENDS = {
  termination: 'termination: black 0 … white 1',
  step: 'step ×: blue finer (÷8) … grey 1 … orange coarser (×8)',
  blend: 'blend: blue fades peaks (−1) … grey 0 … orange fades DVR (+1)',
};

export class TexturePreview {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.scratch = document.createElement('canvas');
  }

  draw(model, channel) {
    const { canvas, ctx } = this;
    if (!model) { ctx.clearRect(0, 0, canvas.width, canvas.height); return; }
    const k = PREVIEW_SIDE / Math.max(model.width, model.height);
    const w = Math.max(1, Math.round(model.width * k)), h = Math.max(1, Math.round(model.height * k));
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    if (this.scratch.width !== model.width || this.scratch.height !== model.height) {
      this.scratch.width = model.width;
      this.scratch.height = model.height;
    }
    const g = this.scratch.getContext('2d');
    const img = g.createImageData(model.width, model.height);
    const c = ['step', 'termination', 'blend'].indexOf(channel);
    for (let i = 0, n = model.width * model.height; i < n; i++) {
      const [r, gg, b] = colour(channel, model.texels[i * 3 + c]);
      img.data[i * 4] = r; img.data[i * 4 + 1] = gg; img.data[i * 4 + 2] = b; img.data[i * 4 + 3] = 255;
    }
    g.putImageData(img, 0, 0);
    ctx.imageSmoothingEnabled = false;
    ctx.drawImage(this.scratch, 0, 0, w, h);
  }
}

export class BrushOutline {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
  }

  clear() { this.ctx.clearRect(0, 0, this.canvas.width, this.canvas.height); }

  // at: {x, y} in CSS pixels over an image of rect.width x rect.height; brush: radius, falloff;
  // texture: {mapping, width, height}; scene: {camera, volume} for the volume mapping.
  draw(at, rect, brush, texture, scene, uv) {
    const dpr = window.devicePixelRatio || 1, c = this.canvas;
    const w = Math.round(rect.width * dpr), h = Math.round(rect.height * dpr);
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const ctx = this.ctx;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, rect.width, rect.height);
    if (!at) return;
    const side = Math.max(texture.width, texture.height);
    // The disk's half-axes in texture units: radius x the larger side, over each side.
    const ru = (brush.radius * side) / texture.width, rv = (brush.radius * side) / texture.height;
    const ring = (k) => {
      const pts = [];
      for (let i = 0; i <= 64; i++) {
        const a = (i / 64) * 2 * Math.PI;
        if (texture.mapping === 'view') pts.push([at.x + Math.cos(a) * ru * k * rect.width, at.y + Math.sin(a) * rv * k * rect.height]);
        else {
          const p = uv && volumeToImage(scene.camera, scene.volume, uv[0] + Math.cos(a) * ru * k, uv[1] + Math.sin(a) * rv * k, rect.width / rect.height);
          pts.push(p ? [p[0] * rect.width, p[1] * rect.height] : null);
        }
      }
      ctx.beginPath();
      let pen = false;
      for (const p of pts) {
        if (!p) { pen = false; continue; }
        if (pen) ctx.lineTo(p[0], p[1]); else ctx.moveTo(p[0], p[1]);
        pen = true;
      }
    };
    const stroke = (style, width, dash) => { ctx.setLineDash(dash); ctx.lineWidth = width; ctx.strokeStyle = style; ctx.stroke(); };
    if (texture.mapping === 'volume' && !uv) {  // the ray misses the volume: nothing to paint here
      ctx.beginPath();
      ctx.arc(at.x, at.y, 6, 0, 2 * Math.PI);
      ctx.moveTo(at.x - 4, at.y - 4); ctx.lineTo(at.x + 4, at.y + 4);
      stroke('#f66', 1.5, []);
      return;
    }
    ring(1);
    stroke('#0009', 3, []);
    stroke('#fff', 1.25, []);
    if (brush.falloff > 0 && brush.falloff < 1) { ring(1 - brush.falloff); stroke('#fffa', 1, [4, 4]); }
    ctx.setLineDash([]);
    ctx.fillStyle = '#fff';
    ctx.fillRect(at.x - 1, at.y - 1, 2, 2);
  }
}
