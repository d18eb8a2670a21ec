#!/usr/bin/env python3
"""A movie made by the server against the client's loop of stills (a benchmark command, not a
test): one `peakcast serve` holding a 256³ volume (blobs, uint8, as bonsai is), an orbit of
`--frames` frames at `--size`² with shaded peaks (or `--classification post`), drawn (a) as the client-python examples do it,
one POST /api/render PNG per frame with the orbit's camera worked out in Python, and (b) as one
POST /api/movie (mp4, and png-zip), in turn for `--rounds` rounds; prints frames per second of
each and the ratio of the medians, movie over loop.

Usage: scripts/bench_movie.py [--build build] [--backend cpu] [--size 512] [--frames 60]
       [--rounds 3] [--data-dir bench-data/movie]
"""
import argparse, math, os, pathlib, re, statistics, subprocess, sys, tempfile, threading, time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "client-python"))
import peakcast  # noqa: E402


def serve(build, backend, data_dir, volume):
    cmd = [str(build / "server/peakcast"), "serve", "--port", "0", "--data", str(data_dir), "--volume", str(volume),
           "--backend", backend, "--max-still-samples", "1e12"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    for line in proc.stdout:
        m = re.search(r"serving on (http://[\d.]+:\d+)", line)
        if m:
            threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
            return proc, m.group(1)
    raise RuntimeError("the server did not start")


def loop(client, scene, info, frames):
    """The examples' way (client-python/examples/orbit.py): a camera per frame, one PNG each."""
    box = [(n - 1) * s for n, s in zip(info["dims"], info["spacing"])]
    center = [o + b / 2 for o, b in zip(info["origin"], box)]
    distance = math.dist(box, (0, 0, 0)) / 2 / math.sin(math.radians(15))
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(frames):
            angle = 2 * math.pi * i / frames
            eye = [center[0] + distance * math.sin(angle), center[1], center[2] + distance * math.cos(angle)]
            s = dict(scene, camera={"eye": eye, "center": center, "up": [0, 1, 0]})
            client.render_png(s, os.path.join(tmp, f"f{i:03d}.png"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--data-dir", type=pathlib.Path, default=ROOT / "bench-data/movie")
    ap.add_argument("--classification", default="peaks", help="post: a cheaper frame, where the per-still costs show")
    a = ap.parse_args()
    a.data_dir.mkdir(parents=True, exist_ok=True)
    volume = a.data_dir / "blobs256.nrrd"
    if not volume.exists():
        subprocess.run([str(a.build / "server/peakcast"), "make-volume", "blobs", "--dims", "256", "256", "256",
                        "--type", "uint8", "-o", str(volume)], check=True, stdout=subprocess.DEVNULL)
    proc, url = serve(a.build, a.backend, a.data_dir, volume)
    try:
        client = peakcast.Client(url)
        info = client.volume("blobs256")
        scene = dict(volume="blobs256", image={"width": a.size, "height": a.size},
                     render={"classification": a.classification, "shading": a.classification == "peaks"})
        client.render(scene)  # the volume resident, the programs built
        ways = {
            "client loop (png)": lambda: loop(client, scene, info, a.frames),
            "movie mp4": lambda: client.movie(scene, os.devnull, orbit={"degrees": 360}, frames=a.frames, format="mp4"),
            "movie png-zip": lambda: client.movie(scene, os.devnull, orbit={"degrees": 360}, frames=a.frames,
                                                  format="png-zip"),
        }
        seconds = {n: [] for n in ways}
        for k in range(a.rounds):
            for n in (list(ways) if k % 2 == 0 else list(reversed(ways))):
                start = time.perf_counter()
                ways[n]()
                seconds[n].append(time.perf_counter() - start)
                print(f"round {k}: {n}: {seconds[n][-1]:.2f} s", flush=True)
    finally:
        proc.terminate()
        proc.wait(30)
    base = statistics.median(seconds["client loop (png)"])
    print(f"\n| {a.frames} frames, {a.size}², {a.backend}, {a.classification}, 256³ | median s | frames/s | / client loop |")
    print("|---|---|---|---|")
    for n, v in seconds.items():
        m = statistics.median(v)
        print(f"| {n} | {m:.2f} | {a.frames / m:.2f} | {base / m:.2f}x |")


if __name__ == "__main__":
    main()
