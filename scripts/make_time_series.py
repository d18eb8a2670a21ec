#!/usr/bin/python3
"""Writes a time series as OME-Zarr (NGFF 0.4, axes t, z, y, x; one uncompressed chunk per time
point): a ball that moves along x over time through a faint gradient, in µm. For the time-series
tests (tests/net/test_time.py, the browser's) and the stepping benchmark (scripts/bench_time.py).

Usage: scripts/make_time_series.py OUT.zarr [--times 20] [--size 64] [--dtype uint16]"""
import argparse
import json
import pathlib

import numpy as np


def ball(t, times, n, dtype):
    z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    cx = n * (0.25 + 0.5 * t / max(1, times - 1))
    r = np.sqrt((x - cx) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2)
    top = np.iinfo(dtype).max if np.issubdtype(dtype, np.integer) else 1.0
    v = 0.1 * top * x / n + 0.8 * top * np.clip(1.0 - r / (0.2 * n), 0, 1)
    return v.astype(dtype)


def write(out, times=20, n=64, dtype="uint16", spacing=(0.5, 0.5, 1.0)):
    out = pathlib.Path(out)
    dt = np.dtype(dtype)
    (out / "0").mkdir(parents=True, exist_ok=False)
    (out / ".zgroup").write_text(json.dumps({"zarr_format": 2}))
    axes = [{"name": "t", "type": "time", "unit": "second"}] + [
        {"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"]
    scale = [1.0, spacing[2], spacing[1], spacing[0]]
    (out / ".zattrs").write_text(json.dumps({"multiscales": [{
        "version": "0.4", "name": out.stem, "axes": axes,
        "datasets": [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": scale}]}]}]}))
    (out / "0" / ".zarray").write_text(json.dumps({
        "zarr_format": 2, "shape": [times, n, n, n], "chunks": [1, n, n, n], "dtype": dt.newbyteorder("<").str,
        "compressor": None, "fill_value": 0, "order": "C", "filters": None}))
    for t in range(times):
        (out / "0" / f"{t}.0.0.0").write_bytes(ball(t, times, n, dt).astype(dt.newbyteorder("<")).tobytes())
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--times", type=int, default=20)
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--dtype", default="uint16")
    a = ap.parse_args()
    write(a.out, a.times, a.size, a.dtype)


if __name__ == "__main__":
    main()
