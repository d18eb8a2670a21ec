"""PNG to numpy with the standard library (zlib): 8-bit, non-interlaced, grey, RGB or RGBA (what
the server writes)."""
import struct
import zlib

import numpy as np

_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}  # PNG colour type -> channels


def decode_png(data):
    """(height, width, channels) uint8."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, head = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            head = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + length
    if head is None:
        raise ValueError("a PNG without its header")
    width, height, depth, colour, _, _, interlace = head
    if depth != 8 or colour not in _CHANNELS or interlace:
        raise ValueError(f"PNG of bit depth {depth}, colour type {colour}, interlace {interlace}: not read here")
    bpp = _CHANNELS[colour]
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), np.uint8).reshape(height, 1 + width * bpp)
    out = np.zeros((height, width * bpp), np.uint8)
    prior = np.zeros(width * bpp, np.uint8)
    for y in range(height):
        kind, line = raw[y, 0], raw[y, 1:]
        out[y] = _unfilter(kind, line, prior, bpp)
        prior = out[y]
    return out.reshape(height, width, bpp)


def _unfilter(kind, line, prior, bpp):
    if kind == 0:
        return line
    if kind == 2:  # up
        return line + prior
    if kind == 1:  # sub: a running sum per channel, modulo 256
        return np.cumsum(line.reshape(-1, bpp).astype(np.int64), axis=0).astype(np.uint8).reshape(-1)
    if kind not in (3, 4):
        raise ValueError(f"PNG filter {kind} is not one of 0..4")
    cur = np.zeros(len(line), np.int64)
    a_row, b_row = line.astype(np.int64), prior.astype(np.int64)
    for i in range(len(line)):
        a = cur[i - bpp] if i >= bpp else 0
        b = b_row[i]
        if kind == 3:  # average
            cur[i] = (a_row[i] + (a + b) // 2) & 255
        else:  # paeth
            c = b_row[i - bpp] if i >= bpp else 0
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            pred = a if pa <= pb and pa <= pc else b if pb <= pc else c
            cur[i] = (a_row[i] + pred) & 255
    return cur.astype(np.uint8)
