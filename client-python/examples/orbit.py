#!/usr/bin/env python3
"""An orbit around a volume, written as numbered PNGs (orbit_000.png, ...), ready for a video tool:
    python3 orbit.py --url http://localhost:8080 --volume heptane_151 --frames 36 --out orbit/"""
import argparse
import math
import os

import peakcast


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--url", default="http://localhost:8080")
    ap.add_argument("--token")
    ap.add_argument("--volume", required=True, help="a volume id (see Client.volumes())")
    ap.add_argument("--frames", type=int, default=36)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--out", default="orbit")
    a = ap.parse_args()
    client = peakcast.Client(a.url, token=a.token)
    info = client.volume(a.volume)
    # The box from the info: centre, and a distance that frames it (VTK's ResetCamera).
    box = [(n - 1) * s for n, s in zip(info["dims"], info["spacing"])]
    center = [o + b / 2 for o, b in zip(info["origin"], box)]
    distance = math.dist(box, (0, 0, 0)) / 2 / math.sin(math.radians(15))
    os.makedirs(a.out, exist_ok=True)
    for i in range(a.frames):
        angle = 2 * math.pi * i / a.frames
        eye = [center[0] + distance * math.sin(angle), center[1] + distance * 0.35, center[2] + distance * math.cos(angle)]
        scene = {"volume": a.volume, "image": {"width": a.size, "height": a.size},
                 "camera": {"eye": eye, "center": center, "up": [0, 1, 0]},
                 "render": {"classification": "peaks", "shading": True}}
        path = os.path.join(a.out, f"orbit_{i:03d}.png")
        client.render_png(scene, path)
        print(path)


if __name__ == "__main__":
    main()
