#!/usr/bin/env python3
"""A transfer-function sweep: an opacity peak moved through the volume's value range, one PNG per
step, to find the isovalue that shows a structure; the steps are key frames of one movie the
server makes (POST /api/movie, a ZIP of PNGs), one request for the whole sweep:
    python3 tf_sweep.py --url http://localhost:8080 --volume heptane_151 --steps 8 --out sweep/"""
import argparse
import os
import zipfile

import peakcast


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--url", default="http://localhost:8080")
    ap.add_argument("--token")
    ap.add_argument("--volume", required=True)
    ap.add_argument("--steps", type=int, default=8)
    ap.add_argument("--size", type=int, default=384)
    ap.add_argument("--out", default="sweep")
    a = ap.parse_args()
    client = peakcast.Client(a.url, token=a.token)
    lo, hi = client.volume(a.volume)["range"]
    os.makedirs(a.out, exist_ok=True)
    keys, isos = [], []
    for i in range(a.steps):
        iso = lo + (hi - lo) * (i + 1) / (a.steps + 1)
        w = (hi - lo) / 200
        keys.append({"tf": {"points": [[lo, 0.2, 0.3, 0.8, 0.0], [iso - w, 0.2, 0.3, 0.8, 0.0],
                                       [iso, 1.0, 0.7, 0.3, 1.0], [iso + w, 0.2, 0.3, 0.8, 0.0],
                                       [hi, 0.2, 0.3, 0.8, 0.0]]}})
        isos.append(iso)
    scene = {"volume": a.volume, "image": {"width": a.size, "height": a.size},
             "render": {"classification": "peaks", "shading": True}}
    # As many frames as keys: frame i is key i exactly (no blend between two isovalues).
    zipped = os.path.join(a.out, "sweep.zip")
    client.movie(scene, zipped, keys=keys, frames=a.steps, format="png-zip")
    with zipfile.ZipFile(zipped) as z:
        for i, name in enumerate(sorted(z.namelist())):
            path = os.path.join(a.out, f"iso_{i:02d}_{isos[i]:.4g}.png")
            with open(path, "wb") as f:
                f.write(z.read(name))
            print(path)
    os.remove(zipped)


if __name__ == "__main__":
    main()
