// Where a point of the image reads the ray texture, mirroring server/core/ray_texture_mapping.h
// and server/core/camera.cpp. Image positions are fractions (fx right, fy down, [0, 1]) of the
// displayed frame; `aspect` is its width / height.
//   view    u = fx, v = fy;
//   volume  the ray's entry point on the volume box (from the first to the last voxel centre),
//           n = p / half-extent from the box centre: u = 1/2 + atan2(n.x, n.z) / 2 pi,
//           v = acos(n.y / |n|) / pi. A ray that misses the box reads no texel (null).
import { add, cross, dot, length, normalize, scale, sub } from './vec.js';

function box(volume) {
  const lo = volume.origin ?? [0, 0, 0];
  const hi = lo.map((o, a) => o + (volume.dims[a] - 1) * (volume.spacing?.[a] ?? 1));
  return { center: lo.map((o, a) => (o + hi[a]) / 2), half: lo.map((o, a) => Math.max((hi[a] - o) / 2, 1e-300)) };
}

// server setup_view: a frame in box-centred coordinates.
function view(camera, volume, aspect) {
  const b = box(volume);
  const forward = normalize(sub(camera.center, camera.eye));
  const right = normalize(cross(forward, camera.up));
  const up = cross(right, forward);
  const ortho = camera.projection === 'orthographic';
  const halfH = ortho ? camera.height / 2 : Math.tan(((camera.fov_y ?? 30) * Math.PI) / 360);
  const eyeRel = sub(camera.eye, b.center);
  const dist = dot(scale(eyeRel, -1), forward);
  return { ...b, forward, right, up, ortho, halfH, halfW: halfH * aspect, eyeRel, dist, p0: add(eyeRel, scale(forward, dist)) };
}

export function viewUv(fx, fy) { return [Math.min(1, Math.max(0, fx)), Math.min(1, Math.max(0, fy))]; }

export function volumeUv(camera, volume, fx, fy, aspect) {
  const v = view(camera, volume, aspect);
  const lateral = add(scale(v.right, (fx * 2 - 1) * v.halfW), scale(v.up, (1 - fy * 2) * v.halfH));
  let o, d, tEye;
  if (v.ortho) {
    o = add(v.p0, lateral); d = v.forward; tEye = -v.dist;
  } else {
    const dd = add(v.forward, lateral), len = length(dd);
    o = add(v.p0, scale(lateral, v.dist)); d = scale(dd, 1 / len); tEye = -v.dist * len;
  }
  let lo = -Infinity, hi = Infinity;
  for (let a = 0; a < 3; a++) {
    const da = Math.abs(d[a]) < 1e-20 ? 1e-20 : d[a];
    let t0 = (-v.half[a] - o[a]) / da, t1 = (v.half[a] - o[a]) / da;
    if (t0 > t1) [t0, t1] = [t1, t0];
    lo = Math.max(lo, t0);
    hi = Math.min(hi, t1);
  }
  const tEnter = Math.max(lo, tEye);
  if (!(tEnter <= hi)) return null;
  const n = add(o, scale(d, tEnter)).map((x, a) => x / v.half[a]);
  const len = length(n);
  if (!(len > 0)) return [0.5, 0.5];
  return [0.5 + Math.atan2(n[0], n[2]) / (2 * Math.PI), Math.acos(Math.min(1, Math.max(-1, n[1] / len))) / Math.PI];
}

// The inverse, for the brush outline: the image position of texture point (u, v) on the box
// surface, or null behind the camera.
export function volumeToImage(camera, volume, u, vv, aspect) {
  const v = view(camera, volume, aspect);
  const phi = 2 * Math.PI * (u - 0.5), theta = Math.PI * vv;
  const dir = [Math.sin(theta) * Math.sin(phi), Math.cos(theta), Math.sin(theta) * Math.cos(phi)];
  const m = Math.max(...dir.map(Math.abs));
  const p = dir.map((x, a) => (x / m) * v.half[a]);  // on the box surface, box-centred
  if (v.ortho) {
    const q = sub(p, v.p0);
    return [(dot(q, v.right) / v.halfW + 1) / 2, (1 - dot(q, v.up) / v.halfH) / 2];
  }
  const rel = sub(p, v.eyeRel), z = dot(rel, v.forward);
  if (!(z > 0)) return null;
  return [(dot(rel, v.right) / (z * v.halfW) + 1) / 2, (1 - dot(rel, v.up) / (z * v.halfH)) / 2];
}
