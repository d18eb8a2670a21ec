#!/usr/bin/env python3
"""A numpy array sent to the server and drawn as a peak-finding isosurface: a gyroid-like field
(an array indexed [z, y, x], spacing in x, y, z order), rendered to an array and saved:
    python3 isosurface.py --url http://localhost:8080 --out isosurface.png"""
import argparse

import numpy as np

import peakcast


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--url", default="http://localhost:8080")
    ap.add_argument("--token")
    ap.add_argument("--n", type=int, default=64, help="voxels per side")
    ap.add_argument("--out", default="isosurface.png")
    a = ap.parse_args()
    z, y, x = np.mgrid[0:a.n, 0:a.n, 0:a.n] * (4 * np.pi / a.n)
    field = (np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)).astype(np.float32)
    client = peakcast.Client(a.url, token=a.token)
    vid = client.upload(field, spacing=(1.0, 1.0, 1.0), name="gyroid")
    try:
        tf = {"points": [[-1.5, 0.1, 0.2, 0.6, 0.0], [-0.02, 0.1, 0.2, 0.6, 0.0], [0.0, 0.95, 0.75, 0.35, 1.0],
                         [0.02, 0.1, 0.2, 0.6, 0.0], [1.5, 0.1, 0.2, 0.6, 0.0]]}
        scene = {"volume": vid, "image": {"width": 512, "height": 512}, "tf": tf,
                 "render": {"classification": "peaks", "shading": True}}
        image = client.render(scene)  # (512, 512, 3) uint8
        client.render_png(scene, a.out)
        print(f"{a.out}: {image.shape}, mean {image.mean():.1f}")
    finally:
        client.delete(vid)


if __name__ == "__main__":
    main()
