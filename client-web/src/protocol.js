// The binary frame header of proto/messages.md (64 bytes, little-endian).
export const FRAME_MAGIC = 0x31464350;
export const FLAG_FINAL = 1, FLAG_INTERACTIVE = 2, FLAG_PNG = 4, FLAG_VIDEO = 8, FLAG_KEY = 16;

export function parseFrame(buffer) {
  const v = new DataView(buffer);
  if (buffer.byteLength < 64 || v.getUint32(0, true) !== FRAME_MAGIC) throw new Error('not a peakcast frame');
  const u64 = (o) => Number(v.getBigUint64(o, true));
  return {
    id: v.getUint32(8, true), flags: v.getUint32(12, true),
    cameraVersion: v.getUint32(16, true), tfVersion: v.getUint32(20, true), renderVersion: v.getUint32(24, true),
    width: v.getUint32(28, true), height: v.getUint32(32, true), quality: v.getUint32(36, true),
    tInputUs: u64(40), tRenderUs: u64(48), tEncodeUs: u64(56),
    get final() { return (this.flags & FLAG_FINAL) !== 0; },
    get png() { return (this.flags & FLAG_PNG) !== 0; },
    get video() { return (this.flags & FLAG_VIDEO) !== 0; },  // one access unit of the session's codec
    get key() { return (this.flags & FLAG_KEY) !== 0; },
    image: new Uint8Array(buffer, 64),
  };
}
