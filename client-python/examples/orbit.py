#!/usr/bin/env python3
"""An orbit around a volume, made by the server (POST /api/movie): a video file, or with --out a
folder of numbered PNGs (orbit_000.png, ...), ready for a video tool of one's own:
    python3 orbit.py --url http://localhost:8080 --volume heptane_151 --frames 36 --movie orbit.mp4
    python3 orbit.py --url http://localhost:8080 --volume heptane_151 --frames 36 --out orbit/"""
import argparse
import os
import tempfile
import zipfile

import peakcast


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--url", default="http://localhost:8080")
    ap.add_argument("--token")
    ap.add_argument("--volume", required=True, help="a volume id (see Client.volumes())")
    ap.add_argument("--frames", type=int, default=36)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--degrees", type=float, default=360)
    ap.add_argument("--movie", help="a .mp4, .webm or .zip (of PNGs) to write")
    ap.add_argument("--out", help="a folder for one PNG a frame")
    a = ap.parse_args()
    client = peakcast.Client(a.url, token=a.token)
    # The server's default camera (a three-quarter view that frames the box, as VTK's), turned
    # about its view up through its focal point, the box's centre.
    scene = {"volume": a.volume, "image": {"width": a.size, "height": a.size},
             "render": {"classification": "peaks", "shading": True}}
    orbit = {"degrees": a.degrees}
    if a.movie:
        info = client.movie(scene, a.movie, orbit=orbit, frames=a.frames)
        print(f"{a.movie}: {info.frames} frames, {info.bytes} bytes ({info.encoder})")
    if a.out or not a.movie:
        out = a.out or "orbit"
        os.makedirs(out, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            pngs = os.path.join(tmp, "frames.zip")
            client.movie(scene, pngs, orbit=orbit, frames=a.frames, format="png-zip")
            with zipfile.ZipFile(pngs) as z:
                for i, name in enumerate(sorted(z.namelist())):
                    path = os.path.join(out, f"orbit_{i:03d}.png")
                    with open(path, "wb") as f:
                        f.write(z.read(name))
                    print(path)


if __name__ == "__main__":
    main()
