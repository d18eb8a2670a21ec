#!/usr/bin/env python3
"""DICOM series (docs/scenes.md, "DICOM") read by peakcast, written here by pydicom with known
values: order by position along the normal (shuffled file names, instance numbers against it),
spacing from PixelSpacing (rows, columns) and the positions, origin from the first position,
rescale applied (HU kept as int16, signed and unsigned, masked to BitsStored), float32 for a
fractional slope, MONOCHROME1 inverted, RLE, JPEG lossless, JPEG-LS and JPEG 2000 decoded, a
choice among two series, and
refusals: uneven spacing (with the gap), gantry tilt, two slices at one place, no choice. No patient
identifier appears in anything peakcast prints.

  dicom_series_test.py PEAKCAST
"""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from dicom_fixtures import PATIENT_ID, PATIENT_NAME, write_series  # noqa: E402

PEAKCAST = sys.argv[1]
failures = []
printed = []  # everything peakcast said: no identifier may be in it


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what)
    if not ok:
        failures.append(what)


def run(*args):
    r = subprocess.run([PEAKCAST, *map(str, args)], capture_output=True, text=True)
    printed.append(r.stdout + r.stderr)
    return r


def convert(src, tmp):
    """The series as peakcast reads it: (array z, y, x; sidecar)."""
    out = os.path.join(tmp, "out.raw")
    r = run("convert", src, out)
    if r.returncode != 0:
        raise RuntimeError(f"convert {src}: {r.stderr.strip()}")
    meta = json.load(open(out + ".json"))
    x, y, z = meta["dims"]
    return np.fromfile(out, dtype=np.dtype(meta["dtype"]).newbyteorder("<")).reshape(z, y, x), meta


def refused(src, *words):
    r = run("info", src)
    ok = r.returncode != 0 and all(w in r.stderr for w in words)
    check(ok, f"{os.path.basename(src)} refused saying {words}: {r.stderr.strip()[-300:]}")


def stack_of(n, rows, cols, f, dtype):
    k, j, i = np.meshgrid(np.arange(n), np.arange(rows), np.arange(cols), indexing="ij")
    return f(k, j, i).astype(dtype)


def ct_coronal(tmp, rle=False):
    """Coronal CT: rows run -z, so the normal is +y; 12 bits stored with junk above them."""
    stored = stack_of(5, 4, 6, lambda k, j, i: 900 + 300 * k + 10 * j + i, np.uint16)
    junk = stored | np.uint16(0xA000)  # bits 13 and 15: above BitsStored, not part of the value
    folder = os.path.join(tmp, "ct_rle" if rle else "ct")
    write_series(folder, junk, positions=[(-50, 10 + 2.5 * k, 30) for k in range(5)], series_uid="1.2.3.4.1",
                 description="Chest 2.5", orientation=(1, 0, 0, 0, 0, -1), spacing=(0.6, 0.8), intercept=-1024,
                 bits_stored=12, rle=rle)
    a, meta = convert(folder, tmp)
    tag = "RLE " if rle else ""
    check(meta["dims"] == [6, 4, 5], f"{tag}coronal CT dims 6x4x5: {meta['dims']}")
    check(meta["dtype"] == "int16", f"{tag}HU kept as int16: {meta['dtype']}")
    check(np.allclose(meta["spacing"], [0.8, 0.6, 2.5]), f"{tag}spacing (columns, rows, gap): {meta['spacing']}")
    check(np.allclose(meta["origin"], [-50, 10, 30]), f"{tag}origin is the first position: {meta['origin']}")
    check(meta.get("values") == "HU", f"{tag}a CT series' values are HU: {meta.get('values')}")
    check(np.array_equal(a, stored.astype(np.int32) - 1024), f"{tag}HU = stored - 1024, ordered by position")
    return folder


def signed_and_float(tmp):
    stored = stack_of(3, 3, 4, lambda k, j, i: -1000 + 1000 * k + 7 * j + i, np.int16)
    folder = os.path.join(tmp, "signed")
    write_series(folder, stored, positions=[(0, 0, -3.0 * k) for k in range(3)], series_uid="1.2.3.4.2",
                 intercept=-1024, spacing=(1.5, 1.5))
    a, meta = convert(folder, tmp)
    check(meta["dtype"] == "int16" and np.array_equal(a, stored[::-1].astype(np.int32) - 1024),
          "signed int16 with intercept -1024: int16 HU, slices ascending along the normal")
    check(np.allclose(meta["origin"], [0, 0, -6]) and np.isclose(meta["spacing"][2], 3.0),
          f"positions descending in the files: origin the lowest along the normal {meta['origin']}")
    folder = os.path.join(tmp, "pet")
    write_series(folder, stored, positions=[(0, 0, k) for k in range(3)], series_uid="1.2.3.4.3", modality="PT",
                 slope=0.25, intercept=1.5)
    a, meta = convert(folder, tmp)
    check(meta["dtype"] == "float32" and np.allclose(a, stored * 0.25 + 1.5),
          f"a fractional slope gives float32 values stored x 0.25 + 1.5: {meta['dtype']}")
    check("values" not in meta, "a PT series is not in HU")


def monochrome1(tmp):
    stored = stack_of(2, 2, 3, lambda k, j, i: 10 + 40 * k + 5 * j + i, np.uint8)
    folder = os.path.join(tmp, "mono1")
    write_series(folder, stored, positions=[(0, 0, k) for k in range(2)], series_uid="1.2.3.4.4", modality="CR",
                 photometric="MONOCHROME1")
    a, meta = convert(folder, tmp)
    lo, hi = int(stored.min()), int(stored.max())
    check(meta["dtype"] == "uint8" and np.array_equal(a, lo + hi - stored.astype(np.int32)),
          "MONOCHROME1 inverted over the series' range, kept uint8")


def compressed(tmp):
    """JPEG lossless, JPEG-LS and JPEG 2000 (gdcmconv, Debian's libgdcm-tools, compresses the
    pydicom-written slices): decoded to the very values; an unsigned MR series stays uint16."""
    stored = stack_of(3, 32, 40, lambda k, j, i: (37 * (1280 * k + 40 * j + i)) % 4000, np.uint16)
    plain = os.path.join(tmp, "mr")
    write_series(plain, stored, positions=[(0, 0, k) for k in range(3)], series_uid="1.2.3.4.8", modality="MR",
                 bits_stored=12)
    for flag, name in (("-J", "JPEG lossless"), ("-L", "JPEG-LS"), ("-K", "JPEG 2000")):
        folder = os.path.join(tmp, "mr" + flag)
        os.makedirs(folder)
        for f in os.listdir(plain):
            subprocess.run(["gdcmconv", flag, os.path.join(plain, f), os.path.join(folder, f)], check=True)
        a, meta = convert(folder, tmp)
        check(meta["dtype"] == "uint16" and np.array_equal(a, stored), f"{name}: the values exactly, uint16")


def refusals(tmp):
    one = np.zeros((2, 2), np.int16)
    for name, positions, words in [
        ("uneven", [(0, 0, z) for z in (0, 1, 2, 4, 5)], ("uneven slice spacing", "2 mm")),
        ("tilted", [(0, 0.5 * k, k) for k in range(4)], ("gantry tilt",)),
        ("twice", [(0, 0, z) for z in (0, 1, 1, 2)], ("two slices at one position",)),
    ]:
        folder = os.path.join(tmp, name)
        write_series(folder, [one] * len(positions), positions=positions, series_uid="1.2.3.9")
        refused(folder, *words)
    for name, pixels, extra, words in [
        ("wide", np.zeros((2, 2), np.uint32), {}, ("32 bits a pixel", "8 and 16")),
        ("colour", one, {"SamplesPerPixel": 3}, ("holds colour (3 samples a pixel)",)),
        ("frames", one, {"NumberOfFrames": 2}, ("multi-frame file (2 frames)",)),
    ]:
        folder = os.path.join(tmp, name)
        write_series(folder, [pixels] * 2, positions=[(0, 0, 0), (0, 0, 1)], series_uid="1.2.3.10", extra=extra)
        refused(folder, *words)


def two_series(tmp):
    folder = os.path.join(tmp, "two")
    soft = stack_of(3, 2, 2, lambda k, j, i: k, np.int16)
    bone = stack_of(4, 2, 2, lambda k, j, i: 100 + k, np.int16)
    write_series(folder, soft, positions=[(0, 0, k) for k in range(3)], series_uid="1.2.3.5.1",
                 description="Soft tissue", seed=2)
    write_series(folder, bone, positions=[(0, 0, k) for k in range(4)], series_uid="1.2.3.5.2",
                 description="Bone", seed=3)
    refused(folder, "2 DICOM series", "'Soft tissue'", "'Bone'", "1.2.3.5.2")
    a, _ = convert(folder + "#Bone", tmp)
    check(a.shape == (4, 2, 2) and a[3, 0, 0] == 103, "FOLDER#DESCRIPTION opens that series")
    a, _ = convert(folder + "#1.2.3.5.1", tmp)
    check(a.shape == (3, 2, 2), "FOLDER#UID opens that series")
    refused(folder + "#Lung", "no series 'Lung'", "'Bone'")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        ct = ct_coronal(tmp)
        ct_coronal(tmp, rle=True)
        r = run("info", ct)
        check("values: HU" in r.stdout and "series: CT 'Chest 2.5'" in r.stdout, "info names the series and HU")
        signed_and_float(tmp)
        monochrome1(tmp)
        compressed(tmp)
        refusals(tmp)
        two_series(tmp)
    said = "\n".join(printed)
    for ident in (PATIENT_NAME, "DOE", PATIENT_ID):
        check(ident not in said, f"no patient identifier ({ident}) in what peakcast printed")
    if failures:
        print(f"{len(failures)} failed")
        sys.exit(1)


if __name__ == "__main__":
    main()
