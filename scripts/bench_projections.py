#!/usr/bin/env python3
"""Projections against DVR on one build (a benchmark command, not a test): the em volume
(900x500x930 u8, bench_ab.py's) drawn by `peakcast-bench scene` as a maximum, minimum and average
intensity projection (a grey ramp TF) and postclassified with bench_ab's narrow band TF (most
cells skipped) and with a dense TF (nothing to skip), all at step 1, in turn for `--rounds`
rounds; prints each median frame and its ratio to the post-classified frames measured in the same
run.

Usage: scripts/bench_projections.py [--build build] [--backend cpu] [--size 1024] [--frames 3]
       [--rounds 2] [--data-dir bench-data/ab]
"""
import argparse, pathlib, statistics, sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import bench_ab  # noqa: E402

EM = bench_ab.SCENES["em"]["vol"]
RAMP = [(0.0, 0, 0, 0, 0), (1.0, 1, 1, 1, 1)]
DENSE = [(0.0, 0.1, 0.1, 0.3, 0.02), (0.5, 0.8, 0.6, 0.3, 0.05), (1.0, 1, 1, 0.9, 0.1)]
SCENES = {
    "post-band": dict(vol=EM, tf=bench_ab.SCENES["em"]["tf"], render={"step": 1}),
    "post-dense": dict(vol=EM, tf=DENSE, render={"step": 1}),
    "mip": dict(vol=EM, tf=RAMP, render={"classification": "mip", "step": 1}),
    "minip": dict(vol=EM, tf=RAMP, render={"classification": "minip", "step": 1}),
    "average": dict(vol=EM, tf=RAMP, render={"classification": "average", "step": 1}),
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", type=pathlib.Path, default=bench_ab.ROOT / "build")
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--data-dir", type=pathlib.Path, default=bench_ab.ROOT / "bench-data/ab")
    a = ap.parse_args()
    a.data_dir.mkdir(parents=True, exist_ok=True)
    files = {n: bench_ab.scene_file("em-" + n, spec, a.build / "server/peakcast", a.data_dir, a.size)
             for n, spec in SCENES.items()}
    ms, samples, variant = {n: [] for n in SCENES}, {}, {}
    for k in range(a.rounds):
        for n in (list(SCENES) if k % 2 == 0 else list(reversed(SCENES))):
            r = bench_ab.time_scene(a.build, bench_ab.ROOT / "shaders", a.backend, files[n], a.frames)
            ms[n].append(r["frame_ms_median"])
            samples[n], variant[n] = r.get("samples_per_ray", float("nan")), r.get("variant", "")
    med = {n: statistics.median(v) for n, v in ms.items()}
    print(f"\n| em {a.size}², {a.backend} | median frame ms | / post (band) | / post (dense) | samples/ray | variant |")
    print("|---|---|---|---|---|---|")
    for n in SCENES:
        print(f"| {n} | {med[n]:.1f} | {med[n] / med['post-band']:.3f} | {med[n] / med['post-dense']:.3f} | "
              f"{samples[n]:.1f} | {variant[n]} |")


if __name__ == "__main__":
    sys.exit(main())
