#!/usr/bin/env python3
"""A/B of two peakcast builds on the ray caster's six reference scenes (a benchmark command, not
a test): each scene is timed with `peakcast-bench scene` by the old build and the new one in
turn, `--rounds` times alternated, on the CPU backend and on GL (llvmpipe here), and the ratio of
the medians new / old is printed per scene and backend.

Scenes (generated volumes, spacing 1): dense post (Marschner-Lobb 128^3 float, a TF that is
nowhere transparent, post @0.75), preint (the same, preintegrated @1), peaks shaded (a narrow
peak, peak classification, shading), tricubic + virtual samples (blobs 256^3 u8, 3 virtual
samples), differential + adaptive (Marschner-Lobb, dense TF), em (900x500x930 u8, a band TF).

With --count, instructions are counted instead of time (the machine's timings scatter by 15%,
instructions do not): each build runs each scene under `valgrind --tool=cachegrind --cache-sim=no`
with --frames 1 and with --frames 3, and (I3 - I1) / 2 is one frame's instructions, whole process
(GL: `LP_NUM_THREADS=1`, the shader being llvmpipe's JIT code). On GL both program caches are
off, so that both runs compile the same programs and the subtraction cancels the compile
(compiling under valgrind takes over 15 minutes a scene; a cache does not help: see
docs/performance.md, "Counting instructions instead of timing").

Usage: scripts/bench_ab.py --old DIR --new DIR [--size 512] [--frames 5] [--rounds 2]
       [--backends cpu,gl] [--scenes LIST] [--data-dir bench-data/ab] [--count]
DIR holds server/peakcast-bench and server/peakcast of a build; --old-shaders / --new-shaders
name the shader folders the builds read (default: DIR/shaders; required where DIR has none).
"""
import argparse, json, math, os, pathlib, re, statistics, subprocess, sys

ROOT = pathlib.Path(__file__).resolve().parents[1]

ML = dict(kind="marschner-lobb", dims=(128, 128, 128), type="float32")
DENSE_TF = [(0.0, 0.1, 0.2, 0.8, 0.0), (0.4, 0.2, 0.6, 0.9, 0.05), (0.7, 0.9, 0.7, 0.3, 0.3), (1.0, 1.0, 1.0, 0.9, 0.6)]
PEAK_TF = [(0.0, 0.2, 0.4, 1.0, 0.0), (0.49, 0.2, 0.4, 1.0, 0.0), (0.5, 1.0, 0.8, 0.3, 0.8), (0.51, 0.2, 0.4, 1.0, 0.0),
           (1.0, 0.2, 0.4, 1.0, 0.0)]
SCENES = {
    "dense-post": dict(vol=ML, tf=DENSE_TF, render={"classification": "post", "step": 0.75}),
    "preint": dict(vol=ML, tf=DENSE_TF, render={"classification": "preint", "step": 1}),
    "peaks-shaded": dict(vol=ML, tf=PEAK_TF, render={"classification": "peaks", "shading": True, "step": 1}),
    "tricubic-vs": dict(vol=dict(kind="blobs", dims=(256, 256, 256), type="uint8"),
                        tf=[(0.0, 0, 0, 0, 0), (0.3, 0.2, 0.4, 1.0, 0.0), (0.6, 1.0, 0.8, 0.4, 0.3), (1.0, 1, 1, 1, 0.6)],
                        render={"filter": "tricubic", "virtual_samples": 3, "step": 2}),
    "diff-adaptive": dict(vol=ML, tf=DENSE_TF, render={"sampling": "differential", "adaptive": True}),
    "em": dict(vol=dict(kind="em", dims=(900, 500, 930), type="uint8"),
               tf=[(0.0, 0, 0, 0, 0), (0.18, 0.9, 0.8, 0.5, 0.0), (0.2, 0.9, 0.8, 0.5, 0.6), (0.22, 0.9, 0.8, 0.5, 0.0),
                   (1.0, 0, 0, 0, 0)],
               render={"step": 1}),
}


def run(cmd, env=None):
    return subprocess.run([str(c) for c in cmd], check=True, capture_output=True, text=True, env=env).stdout


def volume(peakcast, spec, data_dir):
    d = spec["dims"]
    path = data_dir / f"{spec['kind']}_{d[0]}x{d[1]}x{d[2]}_{spec['type']}.mhd"
    if not path.exists():
        print(f"generating {path} ...", flush=True)
        run([peakcast, "make-volume", spec["kind"], "--dims", *d, "--type", spec["type"], "-o", path])
    m = re.search(r"range: (\S+) (\S+)", run([peakcast, "info", path]))
    return path, float(m.group(1)), float(m.group(2))


def scene_file(name, spec, peakcast, data_dir, size):
    path, lo, hi = volume(peakcast, spec["vol"], data_dir)
    d = spec["vol"]["dims"]
    center = [(n - 1) / 2.0 for n in d]
    radius = 0.5 * math.sqrt(sum((n - 1) ** 2 for n in d))
    dist = radius / math.sin(math.radians(15.0))
    view = (0.55, 0.45, 0.7)
    norm = math.sqrt(sum(x * x for x in view))
    scene = {"volume": str(path), "image": {"width": size, "height": size},
             "tf": {"points": [[lo + f * (hi - lo), r, g, b, a] for f, r, g, b, a in spec["tf"]]},
             "camera": {"eye": [c + dist * x / norm for c, x in zip(center, view)], "center": center, "up": [0, 1, 0],
                        "fov_y": 30},
             "render": spec["render"], "background": [0, 0, 0]}
    out = data_dir / f"{name}_{size}.json"
    out.write_text(json.dumps(scene))
    return out


def time_scene(build, shaders, backend, scene, frames):
    env = dict(os.environ, PEAKCAST_BACKEND=backend, PEAKCAST_SHADER_DIR=str(shaders))
    out = run([build / "server/peakcast-bench", "scene", scene, "--frames", frames, "--warmup", 1, "--orbit", 20, "--json"],
              env=env)
    return json.loads(out.strip().splitlines()[-1])


def count_scene(build, shaders, backend, scene, caches):
    """One frame's instructions (whole process) by cachegrind: (frames 3 - frames 1) / 2."""
    env = dict(os.environ, PEAKCAST_BACKEND=backend, PEAKCAST_SHADER_DIR=str(shaders), LP_NUM_THREADS="1")
    # GL: both program caches off, so that both runs compile alike and the difference is frames
    # alone. A cache warmed outside valgrind is not the one a run under it reads (llvmpipe sees
    # other CPU features there, 128-bit vectors), and one warmed under it still gained entries
    # from run to run: counts with caches on came out negative (docs/performance.md).
    if backend == "gl":
        env.update(MESA_SHADER_CACHE_DISABLE="true", PEAKCAST_PROGRAM_CACHE="off")
    bench = [build / "server/peakcast-bench", "scene", scene, "--warmup", 0, "--orbit", 0, "--frames"]
    counts = {}
    for frames in (1, 3):
        out = subprocess.run(["valgrind", "--tool=cachegrind", "--cache-sim=no", "--cachegrind-out-file=/dev/null"]
                             + [str(c) for c in bench + [frames]], env=env, capture_output=True, text=True, check=True)
        counts[frames] = int(re.search(r"I\s+refs:\s+([\d,]+)", out.stderr).group(1).replace(",", ""))
    if counts[3] <= counts[1]:
        raise SystemExit(f"{scene}: 3 frames counted {counts[3]} instructions, 1 frame {counts[1]}: not one frame apart")
    return (counts[3] - counts[1]) / 2.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, type=pathlib.Path)
    ap.add_argument("--new", required=True, type=pathlib.Path)
    ap.add_argument("--old-shaders", type=pathlib.Path)
    ap.add_argument("--new-shaders", type=pathlib.Path)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--backends", default="cpu,gl")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--data-dir", type=pathlib.Path, default=ROOT / "bench-data/ab")
    ap.add_argument("--count", action="store_true", help="count instructions (cachegrind) instead of timing")
    a = ap.parse_args()
    a.data_dir.mkdir(parents=True, exist_ok=True)
    shaders = {}
    for side, build, given in (("old", a.old, a.old_shaders), ("new", a.new, a.new_shaders)):
        shaders[side] = given or (build / "shaders" if (build / "shaders").is_dir() else None)
        if shaders[side] is None:  # the source tree's shaders belong to neither build for sure
            sys.exit(f"bench_ab: no shaders for the {side} build: give --{side}-shaders")
    builds = {"old": a.old, "new": a.new}
    rows = []
    for name in a.scenes.split(","):
        scene = scene_file(name, SCENES[name], a.new / "server/peakcast", a.data_dir, a.size)
        for backend in a.backends.split(","):
            ms = {"old": [], "new": []}
            if a.count:
                for side in ("old", "new"):
                    caches = a.data_dir / f"caches-{side}"
                    ms[side].append(count_scene(builds[side], shaders[side], backend, scene, caches) / 1e6)
            for k in range(0 if a.count else a.rounds):
                for side in (("old", "new") if k % 2 == 0 else ("new", "old")):  # neither always first
                    r = time_scene(builds[side], shaders[side], backend, scene, a.frames)
                    ms[side].append(r["frame_ms_median"])
            old, new = statistics.median(ms["old"]), statistics.median(ms["new"])
            rows.append((name, backend, old, new, new / old, ms))
            unit = "M" if a.count else "ms"
            print(f"{name:14s} {backend:4s} old {old:8.1f} {unit}  new {new:8.1f} {unit}  new/old {new / old:5.3f}   "
                  f"(old {', '.join(f'{x:.1f}' for x in ms['old'])}; new {', '.join(f'{x:.1f}' for x in ms['new'])})",
                  flush=True)
    unit = "M instructions" if a.count else "ms"
    print(f"\n| scene | backend | old {unit} | new {unit} | new / old |\n|---|---|---|---|---|")
    for name, backend, old, new, ratio, _ in rows:
        print(f"| {name} | {backend} | {old:.1f} | {new:.1f} | {ratio:.3f} |")


if __name__ == "__main__":
    sys.exit(main())
