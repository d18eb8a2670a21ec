#!/usr/bin/env python3
"""OME-Zarr and Neuroglancer precomputed against an independent implementation: Debian's
python3-zarr reads what `peakcast convert --pyramid` writes (every level, every compressor; read
whole and by slabs; time series), and
peakcast reads what python3-zarr writes (each compressor and blosc inner codec, both key
separators, big-endian, missing chunks, t and c axes) and precomputed folders written here.

  zarr_interop_test.py PEAKCAST
"""
import gzip
import json
import os
import re
import subprocess
import sys
import tempfile

import numcodecs
import numpy as np
import zarr

PEAKCAST = sys.argv[1]
failures = []


def run(*args):
    r = subprocess.run([PEAKCAST, *map(str, args)], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"peakcast {' '.join(map(str, args))}: {r.stderr.strip()}")
    return r.stdout


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def read_raw(path):
    """A .raw + .raw.json that peakcast wrote, as a (z, y, x) array."""
    meta = json.load(open(path + ".json"))
    dt = np.dtype(meta["dtype"]).newbyteorder("<" if meta.get("endian", "little") == "little" else ">")
    x, y, z = meta["dims"]
    return np.fromfile(path, dtype=dt).reshape(z, y, x)


def halve(a):
    """The writer's next level: 2x2x2 means, sizes rounded up, integers rounded half up."""
    z, y, x = a.shape
    out = np.zeros(((z + 1) // 2, (y + 1) // 2, (x + 1) // 2))
    count = np.zeros_like(out)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                part = a[dz::2, dy::2, dx::2].astype(np.float64)
                out[: part.shape[0], : part.shape[1], : part.shape[2]] += part
                count[: part.shape[0], : part.shape[1], : part.shape[2]] += 1
    mean = out / count
    if a.dtype.kind == "f":
        return mean.astype(a.dtype)
    return np.floor(mean + 0.5).astype(a.dtype)  # half away from zero: the writer rounds shifted values


def peakcast_writes(tmp):
    for kind, dtype in (("blobs", "uint8"), ("blobs", "int8"), ("ramp", "uint16"), ("blobs", "int16"),
                        ("marschner-lobb", "float32")):
        src = os.path.join(tmp, f"{kind}-{dtype}.raw")
        run("make-volume", kind, "--dims", 45, 30, 21, "--type", dtype, "--spacing", 0.5, 1, 2, "-o", src)
        want = read_raw(src)
        for comp in ("blosc", "zstd", "zlib", "gzip", "none"):
            out = os.path.join(tmp, f"{kind}-{dtype}-{comp}.zarr")
            run("convert", src, out, "--pyramid", "--chunk", 16, "--compressor", comp)
            group = zarr.open_group(out, mode="r")
            ms = group.attrs["multiscales"][0]
            paths = [d["path"] for d in ms["datasets"]]
            check(ms["version"] == "0.4" and [a["name"] for a in ms["axes"]] == ["z", "y", "x"],
                  f"{dtype} {comp}: NGFF 0.4 multiscales with axes z, y, x")
            level = want
            for i, p in enumerate(paths):
                got = group[p][...]
                scale = ms["datasets"][i]["coordinateTransformations"][0]["scale"]
                if i > 0:
                    level = halve(level) if dtype[0] != "i" else halve_signed(level)
                same = got.dtype == level.dtype and got.shape == level.shape and np.array_equal(got, level)
                check(same and scale == [2.0 * 2**i, 1.0 * 2**i, 0.5 * 2**i],
                      f"{dtype} {comp}: level {i} {got.shape} read by python3-zarr equals the "
                      f"{'source' if i == 0 else 'mean of the level above'}")
            check(len(paths) == 3, f"{dtype} {comp}: 45x30x21 in 16-voxel chunks makes 3 levels ({len(paths)})")


def peakcast_writes_by_slabs(tmp):
    """An input larger than convert's memory budget is read by slabs: python3-zarr reads the same
    pyramid as from a whole read."""
    for dtype in ("uint16", "float32"):
        src = os.path.join(tmp, f"slabs-{dtype}.raw")
        run("make-volume", "blobs", "--dims", 150, 140, 70, "--type", dtype, "-o", src)  # 2.8 / 5.6 MiB
        want = read_raw(src)
        out = os.path.join(tmp, f"slabs-{dtype}.zarr")
        said = run("convert", src, out, "--pyramid", "--chunk", 32, "--memory-budget-mib", 1)
        check("read by slabs of 32 planes" in said, f"{dtype}: convert says it read by slabs ({said.strip()})")
        group = zarr.open_group(out, mode="r")
        paths = [d["path"] for d in group.attrs["multiscales"][0]["datasets"]]
        level = want
        for i, p in enumerate(paths):
            level = level if i == 0 else halve(level)
            got = group[p][...]
            check(got.dtype == level.dtype and np.array_equal(got, level),
                  f"{dtype} by slabs: level {i} {got.shape} read by python3-zarr equals the "
                  f"{'source' if i == 0 else 'mean of the level above'}")
        check(len(paths) == 4, f"{dtype} by slabs: 150x140x70 in 32-voxel chunks makes 4 levels ({len(paths)})")
    # A TIFF stack has no region reads: convert reads it whole, whatever the budget.
    from PIL import Image
    pages = [np.full((30, 40), 10 * k + 1, dtype=np.uint8) for k in range(3)]
    tif = os.path.join(tmp, "pages.tif")
    Image.fromarray(pages[0]).save(tif, save_all=True, append_images=[Image.fromarray(p) for p in pages[1:]])
    out = os.path.join(tmp, "pages.zarr")
    run("convert", tif, out, "--memory-budget-mib", 1)
    got = zarr.open_group(out, mode="r")["0"][...]
    check(np.array_equal(got, np.stack(pages)), f"a TIFF stack is converted whole {got.shape}")
    # The budget is for an OME-Zarr output, and positive: refused by name, nothing written.
    for args, words in (([tif, os.path.join(tmp, "pages.nrrd"), "--memory-budget-mib", 1], "is for an OME-Zarr output"),
                        ([tif, os.path.join(tmp, "zero.zarr"), "--memory-budget-mib", 0], "memory-budget-mib")):
        r = subprocess.run([PEAKCAST, "convert", *map(str, args)], capture_output=True, text=True)
        check(r.returncode != 0 and words in r.stderr and not os.path.exists(str(args[1])),
              f"convert {' '.join(map(str, args[2:]))} to {os.path.basename(str(args[1]))} is refused: {r.stderr.strip()}")


def write_series(tmp, name, series, extra=None):
    """A raw time series (t, z, y, x) with its sidecar."""
    path = os.path.join(tmp, name + ".raw")
    series.astype(series.dtype.newbyteorder("<")).tofile(path)
    t, z, y, x = series.shape
    json.dump({"dims": [x, y, z], "dtype": {"u2": "uint16", "f4": "float32"}[series.dtype.str[1:]], "times": t,
               **(extra or {})}, open(path + ".json", "w"))
    return path


def peakcast_writes_series(tmp):
    """convert --pyramid keeps a time series (a t axis, every level holding each time point), its
    spacing and its unit; each time point is the pyramid of that time point alone."""
    rng = np.random.default_rng(5)
    u16 = rng.integers(0, 60000, size=(3, 21, 30, 45)).astype("<u2")
    f32 = (rng.standard_normal((2, 21, 30, 45)) * 10).astype("<f4")
    f32[1, 3, 4, 5] = np.nan  # replaced by time point 1's own finite minimum, as a read of it alone
    for series, name in ((u16, "series-u16"), (f32, "series-f32")):
        src = write_series(tmp, name, series, {"spacing": [0.5, 1, 2], "units": "um"})
        out = os.path.join(tmp, name + ".zarr")
        said = run("convert", src, out, "--pyramid", "--chunk", 16)
        group = zarr.open_group(out, mode="r")
        ms = group.attrs["multiscales"][0]
        axes = [(a["name"], a["type"], a.get("unit")) for a in ms["axes"]]
        check(axes == [("t", "time", None)] + [(n, "space", "micrometer") for n in "zyx"] and
              f"x {len(series)} time points" in said, f"{name}: axes t, z, y, x in micrometres ({said.strip()})")
        for t in range(len(series)):
            level = series[t]
            if level.dtype.kind == "f":
                level = np.where(np.isnan(level), np.nanmin(level), level)
            for i, d in enumerate(ms["datasets"]):
                level = level if i == 0 else halve(level)
                got = group[d["path"]][...]
                scale = d["coordinateTransformations"][0]["scale"]
                check(got.shape == (len(series),) + level.shape and np.array_equal(got[t], level) and
                      scale == [1.0, 2.0 * 2**i, 1.0 * 2**i, 0.5 * 2**i],
                      f"{name}: time point {t}, level {i} {got.shape[1:]} read by python3-zarr equals its own "
                      f"{'voxels' if i == 0 else 'mean of the level above'}")
        back = os.path.join(tmp, name + "-t1.raw")
        run("convert", out, back, "--time", 1)
        want = series[1] if series.dtype.kind != "f" else np.where(np.isnan(series[1]), np.nanmin(series[1]), series[1])
        check(np.array_equal(read_raw(back), want), f"{name}: peakcast reads time point 1 of what it wrote")
    # --time picks one time point: no t axis.
    one = os.path.join(tmp, "one.zarr")
    run("convert", os.path.join(tmp, "series-u16.raw"), one, "--time", 2)
    g = zarr.open_group(one, mode="r")
    check([a["name"] for a in g.attrs["multiscales"][0]["axes"]] == ["z", "y", "x"] and np.array_equal(g["0"][...], u16[2]),
          "convert --time 2 writes that time point alone (axes z, y, x)")
    # A format of one time point would lose the rest: refused, naming --time, nothing written.
    nrrd = os.path.join(tmp, "series.nrrd")
    r = subprocess.run([PEAKCAST, "convert", os.path.join(tmp, "series-u16.raw"), nrrd], capture_output=True, text=True)
    check(r.returncode != 0 and "holds 3 time points" in r.stderr and "--time" in r.stderr and not os.path.exists(nrrd),
          f"a series to .nrrd without --time is refused: {r.stderr.strip()}")
    # An ImageJ hyperstack (read only whole): one time point at a time, ImageJ's page order.
    from PIL import Image
    frames = rng.integers(0, 255, size=(2, 3, 12, 10)).astype(np.uint8)  # t, z, y, x
    tif = os.path.join(tmp, "hyper.tif")
    pages = [Image.fromarray(frames[t, z]) for t in range(2) for z in range(3)]
    pages[0].save(tif, save_all=True, append_images=pages[1:],
                  tiffinfo={270: "ImageJ=1.54f\nimages=6\nslices=3\nframes=2\nhyperstack=true\n"})
    out = os.path.join(tmp, "hyper.zarr")
    run("convert", tif, out, "--memory-budget-mib", 1)
    got = zarr.open_group(out, mode="r")["0"][...]
    check(np.array_equal(got, frames), f"an ImageJ hyperstack is converted with its time axis {got.shape}")


def halve_signed(a):
    """Signed types are kept shifted to unsigned (int8 + 128): the mean is rounded there."""
    bits = a.dtype.itemsize * 8
    shifted = a.astype(np.int64) + (1 << (bits - 1))
    return (halve(shifted.astype(np.uint64 if bits > 8 else np.uint16)).astype(np.int64) - (1 << (bits - 1))).astype(a.dtype)


def python_writes(tmp):
    rng = np.random.default_rng(3)
    compressors = [None, numcodecs.Zlib(level=3), numcodecs.GZip(level=5), numcodecs.Zstd(level=3)]
    for cname in ("lz4", "zstd", "blosclz", "zlib", "lz4hc"):
        for shuffle in (numcodecs.Blosc.NOSHUFFLE, numcodecs.Blosc.SHUFFLE, numcodecs.Blosc.BITSHUFFLE):
            compressors.append(numcodecs.Blosc(cname=cname, clevel=5, shuffle=shuffle))
    dtypes = ["<u2", "|u1", "|i1", "<i2", "<f4", ">u2", ">f4"]
    for n, comp in enumerate(compressors):
        dt = np.dtype(dtypes[n % len(dtypes)])
        sep = "/" if n % 2 else "."
        a = (rng.integers(0, 250, size=(13, 17, 19)) - (100 if dt.kind == "i" else 0)).astype(dt)
        if dt.kind == "f":
            a = (rng.standard_normal((13, 17, 19)) * 10).astype(dt)
        path = os.path.join(tmp, f"py{n}.zarr")
        store = zarr.DirectoryStore(path, dimension_separator=sep)
        z = zarr.create(shape=a.shape, chunks=(5, 6, 7), dtype=dt, compressor=comp, store=store, fill_value=3)
        z[...] = a
        # a chunk python3-zarr does not store (or one removed) reads as the fill value
        key = "2/2/2" if sep == "/" else "2.2.2"
        os.remove(os.path.join(path, key))
        a[10:13, 12:17, 14:19] = 3
        out = os.path.join(tmp, f"py{n}.raw")
        run("convert", path, out)
        got = read_raw(out)
        check(np.array_equal(got.astype(np.float64), a.astype(np.float64)),
              f"python3-zarr {dt.str} {comp!r} sep '{sep}' read by peakcast (a missing chunk as fill_value)")
    # An OME-Zarr image with t and c axes and two levels, as ome-zarr-py lays it out.
    path = os.path.join(tmp, "tczyx.zarr")
    root = zarr.open_group(zarr.DirectoryStore(path, dimension_separator="/"), mode="w")
    data = rng.integers(0, 60000, size=(3, 2, 9, 10, 11)).astype("<u2")
    root.create_dataset("s0", data=data, chunks=(1, 1, 4, 5, 6), compressor=numcodecs.Blosc(cname="zstd"))
    root.create_dataset("s1", data=data[:, :, ::2, ::2, ::2], chunks=(1, 1, 4, 5, 6))
    axes = [{"name": "t", "type": "time"}, {"name": "c", "type": "channel"}] + \
           [{"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"]
    root.attrs["multiscales"] = [{"version": "0.4", "axes": axes, "datasets": [
        {"path": f"s{i}", "coordinateTransformations": [{"type": "scale", "scale": [1, 1, 0.4 * 2**i, 0.2 * 2**i, 0.1 * 2**i]}]}
        for i in (0, 1)]}]
    for t, c, level in ((0, 0, 0), (2, 1, 0), (1, 1, 1)):
        out = os.path.join(tmp, f"tc{t}{c}{level}.raw")
        run("convert", path, out, "--time", t, "--channel", c, "--level", level)
        want = data[t, c] if level == 0 else data[t, c, ::2, ::2, ::2]
        meta = json.load(open(out + ".json"))
        check(np.array_equal(read_raw(out), want) and np.allclose(meta["spacing"], [0.1 * 2**level, 0.2 * 2**level, 0.4 * 2**level]),
              f"OME-Zarr t={t} c={c} level {level}: voxels and spacing")


def precomputed(tmp):
    root = os.path.join(tmp, "ng")
    key = "8_8_40"
    os.makedirs(os.path.join(root, key))
    size, chunk, offset = (21, 14, 9), (8, 8, 4), (16, 0, 4)
    vol = np.arange(size[0] * size[1] * size[2], dtype="<u2").reshape(size[2], size[1], size[0]) * 7
    json.dump({"@type": "neuroglancer_multiscale_volume", "type": "image", "data_type": "uint16", "num_channels": 1,
               "scales": [{"key": key, "size": list(size), "resolution": [8, 8, 40], "voxel_offset": list(offset),
                           "chunk_sizes": [list(chunk)], "encoding": "raw"}]}, open(os.path.join(root, "info"), "w"))
    n = 0
    for z0 in range(0, size[2], chunk[2]):
        for y0 in range(0, size[1], chunk[1]):
            for x0 in range(0, size[0], chunk[0]):
                x1, y1, z1 = min(x0 + chunk[0], size[0]), min(y0 + chunk[1], size[1]), min(z0 + chunk[2], size[2])
                block = vol[z0:z1, y0:y1, x0:x1].tobytes()
                name = f"{x0 + offset[0]}-{x1 + offset[0]}_{y0 + offset[1]}-{y1 + offset[1]}_{z0 + offset[2]}-{z1 + offset[2]}"
                n += 1
                if n % 3 == 0:
                    open(os.path.join(root, key, name + ".gz"), "wb").write(gzip.compress(block))
                elif n % 3 == 1:
                    open(os.path.join(root, key, name), "wb").write(gzip.compress(block))
                else:
                    open(os.path.join(root, key, name), "wb").write(block)
    out = os.path.join(tmp, "ng.raw")
    run("convert", root, out)
    meta = json.load(open(out + ".json"))
    check(np.array_equal(read_raw(out), vol) and meta["spacing"] == [8, 8, 40] and meta["origin"] == [132, 4, 180],
          "Neuroglancer precomputed (raw, gzip and .gz chunks): voxels, spacing (nm) and origin (first voxel's centre)")


def info_reads_within_a_budget(tmp):
    """`peakcast info` of a pyramid reads its finest level within --memory-budget-mib (256 MiB when
    not given), not level 0 whatever its size; --level names a level."""
    src, out = os.path.join(tmp, "info-blobs.raw"), os.path.join(tmp, "info-blobs.zarr")
    run("make-volume", "blobs", "--dims", 160, 150, 140, "--type", "uint16", "-o", src)  # 6.4 MiB
    run("convert", src, out, "--pyramid", "--chunk", 32)
    rss = lambda text: float(re.search(r"peak RSS: ([\d.]+) MiB", text).group(1))
    small = run("info", out, "--memory-budget-mib", 1)
    whole = run("info", out)
    named = run("info", out, "--level", 2)
    check("read: level 1 of 0..3, the finest within 1 MiB" in small and "dims: 80 75 70" in small,
          "info --memory-budget-mib 1 reads level 1 (80x75x70, 0.8 MiB)")
    check("read: level 0 of 0..3, the finest within 256 MiB" in whole and "dims: 160 150 140" in whole,
          "info without a budget reads level 0 where it fits in 256 MiB")
    check("read: level 2 of 0..3;" in named and "dims: 40 38 35" in named, "info --level 2 reads level 2")
    check(rss(small) < rss(whole), f"info within 1 MiB peaks lower ({rss(small)} MiB) than of level 0 ({rss(whole)} MiB)")


with tempfile.TemporaryDirectory() as tmp:
    info_reads_within_a_budget(tmp)
    peakcast_writes(tmp)
    peakcast_writes_by_slabs(tmp)
    peakcast_writes_series(tmp)
    python_writes(tmp)
    precomputed(tmp)
print(f"{len(failures)} failed" if failures else "all passed")
sys.exit(1 if failures else 0)
