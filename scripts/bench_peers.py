#!/usr/bin/env python3
"""bench peers: peakcast against VTK's CPU and GPU volume mappers, side by side, at equal error.

A benchmark command, not a test. For each scene (volume, TF, camera, image size) it
renders, in one run:
  - VTK vtkFixedPointVolumeRayCastMapper (CPU) and vtkOpenGLGPUVolumeRayCastMapper (on whatever
    GL the X server offers: llvmpipe under Xvfb here), both at the scene's sample distance (one
    voxel), AutoAdjustSampleDistances off, image sample distance 1, no jitter, the same opacity
    unit distance as peakcast's scene (the smallest spacing);
  - a converged image: VTK's GPU mapper at 1/20 voxel (the issue's reference);
  - peakcast (`peakcast-bench scene --json` for time, `peakcast render` for the image) at several
    steps, and reports for each VTK mapper the fastest peakcast step whose PSNR against the
    converged image is at least that mapper's: "at equal error".
Frame times are medians over an orbit (--frames frames over --orbit degrees) after warm-up;
VTK's time is Render() + glFinish, peakcast's the whole frame with its 8-bit read-back.

With --backends cpu,gl, peakcast's candidates run under each backend (PEAKCAST_BACKEND) in the
same run, one row each; the default is whatever auto chooses on this machine.

It follows an independent protocol: post and preint candidates at steps 0.5, 0.75, 1, 1.5, 2, 3
and 4 voxels for every scene, each timed as `peakcast-bench scene --frames 5 --orbit 20` and scored
by `peakcast render` at the first camera; VTK at 1 voxel, timed over the same 5 frames after two
warm-up renders. It adds the blobs scene to the protocol's Marschner-Lobb and em.

Usage: scripts/bench_peers.py [--peakcast build/server/peakcast] [--sizes 512,1024]
       [--scenes blobs,ml-peak,ml-dense,em,em-dense] [--frames 5] [--no-preint] [--steps LIST] [--data-dir bench-data/peers]
       [--backends auto] [--ring-px 4]
Runs itself under xvfb-run when there is no DISPLAY. Needs python3-vtk9 and python3-pil.
"""
import argparse, json, math, os, pathlib, re, shutil, statistics, subprocess, sys, tempfile, time

ROOT = pathlib.Path(__file__).resolve().parents[1]

# name: volume generator args, TF (as fractions of the value range), camera direction, peakcast
# render settings.
# peakcast's candidate steps (voxels), for every scene: the independent protocol's.
STEPS = [0.5, 0.75, 1, 1.5, 2, 3, 4]
SCENES = {
    "blobs": dict(kind="blobs", dims=(256, 256, 256), type="uint8",
                  tf=[(0.0, 0, 0, 0, 0), (0.3, 0.2, 0.4, 1.0, 0.0), (0.6, 1.0, 0.8, 0.4, 0.3), (1.0, 1, 1, 1, 0.6)],
                  view=(0.55, 0.45, 0.7), render={}),
    "ml-peak": dict(kind="marschner-lobb", dims=(128, 128, 128), type="float32",
                    tf=[(0.0, 0.2, 0.4, 1.0, 0.0), (0.49, 0.2, 0.4, 1.0, 0.0), (0.5, 1.0, 0.8, 0.3, 0.8),
                        (0.51, 0.2, 0.4, 1.0, 0.0), (1.0, 0.2, 0.4, 1.0, 0.0)],
                    view=(0.55, 0.45, 0.7), render={}),
    # Nowhere transparent: every cell occupied, no space skipping, as on a dense real volume; the
    # kind of TF the independent measure's Marschner-Lobb row used (VTK fixed-point near 37 dB).
    "ml-dense": dict(kind="marschner-lobb", dims=(128, 128, 128), type="float32",
                     tf=[(0.0, 0.1, 0.2, 0.8, 0.0), (0.4, 0.2, 0.6, 0.9, 0.05), (0.7, 0.9, 0.7, 0.3, 0.3),
                         (1.0, 1.0, 1.0, 0.9, 0.6)],
                     view=(0.55, 0.45, 0.7), render={}),
    "em": dict(kind="em", dims=(900, 500, 930), type="uint8",
               # the quality suite's em_band (tests/bench/quality/em_band.json): a band at 0.2 of the range
               tf=[(0.0, 0, 0, 0, 0), (0.18, 0.9, 0.8, 0.5, 0.0), (0.2, 0.9, 0.8, 0.5, 0.6), (0.22, 0.9, 0.8, 0.5, 0.0),
                   (1.0, 0, 0, 0, 0)],
               view=(0.55, 0.45, 0.7), render={}),
    # em with a dense TF (scripts/bench_projections.py's): every value somewhat opaque, nothing to
    # skip, the independent measure's em case (there peakcast took 0.95 of fixed-point's time at
    # 1024², where the band above skips most of the volume).
    "em-dense": dict(kind="em", dims=(900, 500, 930), type="uint8",
                     tf=[(0.0, 0.1, 0.1, 0.3, 0.02), (0.5, 0.8, 0.6, 0.3, 0.05), (1.0, 1, 1, 0.9, 0.1)],
                     view=(0.55, 0.45, 0.7), render={}),
}


def run(cmd, **kw):
    return subprocess.run([str(c) for c in cmd], check=True, capture_output=True, text=True, **kw).stdout


def value_range(peakcast, volume):
    m = re.search(r"range: (\S+) (\S+)", run([peakcast, "info", volume]))
    return float(m.group(1)), float(m.group(2))


def make_volume(peakcast, name, spec, data_dir):
    d = spec["dims"]
    path = data_dir / f"{spec['kind']}_{d[0]}x{d[1]}x{d[2]}_{spec['type']}.mhd"
    if not path.exists():
        print(f"generating {path} ...", flush=True)
        run([peakcast, "make-volume", spec["kind"], "--dims", *d, "--type", spec["type"], "-o", path])
    return path


def scene_json(spec, volume, lo, hi, size, step):
    pts = [[lo + f * (hi - lo), r, g, b, a] for f, r, g, b, a in spec["tf"]]
    d = spec["dims"]
    center = [(n - 1) / 2.0 for n in d]  # spacing 1, origin 0
    radius = 0.5 * math.sqrt(sum((n - 1) ** 2 for n in d))
    dist = radius / math.sin(math.radians(15.0))  # VTK's ResetCamera distance for a 30-degree view
    v = spec["view"]
    norm = math.sqrt(sum(x * x for x in v))
    eye = [c + dist * x / norm for c, x in zip(center, v)]
    return {"volume": str(volume), "image": {"width": size, "height": size}, "tf": {"points": pts},
            "camera": {"eye": eye, "center": center, "up": [0, 1, 0], "fov_y": 30},
            "render": dict(spec["render"], step=step), "background": [0, 0, 0]}


def psnr(a_path, b_path):
    from PIL import Image, ImageChops
    a, b = Image.open(a_path).convert("RGB"), Image.open(b_path).convert("RGB")
    hist = ImageChops.difference(a, b).histogram()
    se = sum(count * ((i % 256) ** 2) for i, count in enumerate(hist))
    n = a.width * a.height * 3
    return 200.0 if se == 0 else 20 * math.log10(255.0 / math.sqrt(se / n))


def psnr_split(a_path, ref_path, ring_px):
    """PSNR inside the volume's outline, `ring_px` pixels in from it, and in that ring alone. The
    outline is where the converged image leaves the (black) background."""
    import numpy as np
    from PIL import Image
    a = np.asarray(Image.open(a_path).convert("RGB"), dtype=np.float64)
    ref = np.asarray(Image.open(ref_path).convert("RGB"), dtype=np.float64)
    inside = ref.sum(axis=2) > 0
    core = inside.copy()
    for _ in range(ring_px):  # erode by one pixel (4-neighbourhood) per round
        core &= np.roll(core, 1, 0) & np.roll(core, -1, 0) & np.roll(core, 1, 1) & np.roll(core, -1, 1)
    se = ((a - ref) ** 2).sum(axis=2) / 3.0
    db = lambda m: 200.0 if not m.any() or se[m].mean() == 0 else 10 * math.log10(255.0 ** 2 / se[m].mean())
    return db(core), db(inside & ~core)


def vtk_render(scene, mapper_kind, step, frames, orbit, out_png):
    """Renders `scene` with a VTK mapper; returns per-frame ms (Render + glFinish) after warm-up."""
    import vtk
    t_load = time.perf_counter()
    r = vtk.vtkMetaImageReader()
    r.SetFileName(scene["volume"])
    r.Update()
    img = r.GetOutput()
    ctf, otf = vtk.vtkColorTransferFunction(), vtk.vtkPiecewiseFunction()
    for v, cr, cg, cb, a in scene["tf"]["points"]:
        ctf.AddRGBPoint(v, cr, cg, cb)
        otf.AddPoint(v, a)
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    prop.SetScalarOpacityUnitDistance(min(img.GetSpacing()))
    if mapper_kind == "fixed-point":
        mapper = vtk.vtkFixedPointVolumeRayCastMapper()
        mapper.SetNumberOfThreads(os.cpu_count() or 1)
    else:
        mapper = vtk.vtkOpenGLGPUVolumeRayCastMapper()
        mapper.SetUseJittering(0)
    mapper.SetInputData(img)
    mapper.SetAutoAdjustSampleDistances(0)
    mapper.SetSampleDistance(step)
    mapper.SetImageSampleDistance(1.0)
    vol = vtk.vtkVolume()
    vol.SetMapper(mapper)
    vol.SetProperty(prop)
    ren = vtk.vtkRenderer()
    ren.AddVolume(vol)
    ren.SetBackground(*scene["background"])
    cam, c = ren.GetActiveCamera(), scene["camera"]
    cam.SetPosition(*c["eye"])
    cam.SetFocalPoint(*c["center"])
    cam.SetViewUp(*c["up"])
    cam.SetViewAngle(c["fov_y"])
    ren.ResetCameraClippingRange()
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(ren)
    win.SetSize(scene["image"]["width"], scene["image"]["height"])
    for k in range(2):  # warm-up: upload, shader compile
        win.Render()
        win.WaitForCompletion()
        if k == 0:
            load_first_ms = (time.perf_counter() - t_load) * 1000.0
    w2i = vtk.vtkWindowToImageFilter()
    w2i.SetInput(win)
    w2i.ReadFrontBufferOff()
    w2i.Update()
    wr = vtk.vtkPNGWriter()
    wr.SetFileName(str(out_png))
    wr.SetInputConnection(w2i.GetOutputPort())
    wr.Write()
    times = []
    for f in range(frames):
        if f > 0:
            cam.Azimuth(orbit / max(1, frames - 1))
            ren.ResetCameraClippingRange()
        t0 = time.perf_counter()
        win.Render()
        win.WaitForCompletion()
        times.append((time.perf_counter() - t0) * 1000.0)
    return times, load_first_ms


def vtk_child(args):
    scene = json.loads(pathlib.Path(args.vtk_scene).read_text())
    times, load_first_ms = vtk_render(scene, args.vtk_mapper, args.vtk_step, args.frames, args.orbit, args.vtk_out)
    print(json.dumps({"times": times, "load_first_ms": load_first_ms}))


def vtk_case(scene_path, mapper, step, frames, orbit, out_png):
    # Each VTK render in its own process: a fresh GL context and no mapper state carried over.
    out = run([sys.executable, __file__, "--vtk-scene", scene_path, "--vtk-mapper", mapper, "--vtk-step", step,
               "--vtk-out", out_png, "--frames", frames, "--orbit", orbit])
    j = json.loads(out.strip().splitlines()[-1])
    return statistics.median(j["times"]), j["load_first_ms"]


def peakcast_case(peakcast, scene_path, frames, orbit, out_png, backend):
    env = dict(os.environ, PEAKCAST_BACKEND=backend)
    run([peakcast, "render", scene_path, "-o", out_png], env=env)
    bench = str(pathlib.Path(peakcast).with_name("peakcast-bench"))
    j = json.loads(run([bench, "scene", scene_path, "--frames", frames, "--orbit", orbit, "--json"], env=env))
    return j


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--peakcast", default=str(ROOT / "build/server/peakcast"),
                    help="the peakcast executable; peakcast-bench is taken from beside it")
    ap.add_argument("--sizes", default="512,1024")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--orbit", type=float, default=20.0)
    ap.add_argument("--data-dir", default=str(ROOT / "bench-data/peers"))
    ap.add_argument("--converged-step", type=float, default=0.05, help="voxels, VTK GPU mapper")
    ap.add_argument("--keep", help="keep the images in this directory")
    ap.add_argument("--no-preint", action="store_true", help="postclassified candidates only (default: also "
                    "preintegrated ones, DVR of the same TF)")
    ap.add_argument("--preint", action="store_true", help="(the default now; accepted so recorded commands still run)")
    ap.add_argument("--steps", help="candidate steps in voxels, e.g. 1,2,4 (default: " + ",".join(map(str, STEPS)) + ")")
    ap.add_argument("--backends", default="auto", help="peakcast backends to compare, e.g. cpu,gl")
    ap.add_argument("--ring-px", type=int, default=0, help="also print each image's PSNR inside the volume's "
                    "outline less this many pixels, and in that ring alone (where the error sits)")
    ap.add_argument("--vtk-scene")
    ap.add_argument("--vtk-mapper")
    ap.add_argument("--vtk-step", type=float)
    ap.add_argument("--vtk-out")
    args = ap.parse_args()
    if args.vtk_scene:
        return vtk_child(args)
    if not os.environ.get("DISPLAY") and shutil.which("xvfb-run"):
        os.execvp("xvfb-run", ["xvfb-run", "-a", "-s", "-screen 0 1280x1280x24", sys.executable, __file__,
                               *sys.argv[1:]])
    data_dir = pathlib.Path(args.data_dir)
    data_dir.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(args.keep) if args.keep else pathlib.Path(tempfile.mkdtemp(prefix="peers-"))
    work.mkdir(parents=True, exist_ok=True)
    rows = []
    backends = args.backends.split(",")
    print(f"{'scene':<8} {'size':>5} {'mapper':<11} {'step':>5} {'ms':>8} {'PSNR':>6} | {'backend':<7} {'pc step':>7} "
          f"{'pc ms':>8} {'pc PSNR':>7} {'spr':>6} {'ratio':>6} | {'peaks ms':>8} {'ratio':>6}", flush=True)
    for name in args.scenes.split(","):
        spec = SCENES[name]
        volume = make_volume(args.peakcast, name, spec, data_dir)
        lo, hi = value_range(args.peakcast, volume)
        for size in [int(s) for s in args.sizes.split(",")]:
            tag = f"{name}_{size}"
            ref_scene = work / f"{tag}_ref.json"
            ref_scene.write_text(json.dumps(scene_json(spec, volume, lo, hi, size, args.converged_step)))
            ref_png = work / f"{tag}_converged.png"
            vtk_case(ref_scene, "gpu", args.converged_step, 1, 0, ref_png)
            load_first = {}
            for mapper in ("fixed-point", "gpu"):
                sp = work / f"{tag}_vtk.json"
                sp.write_text(json.dumps(scene_json(spec, volume, lo, hi, size, 1.0)))
                png = work / f"{tag}_vtk_{mapper}.png"
                vtk = vtk_case(sp, mapper, 1.0, args.frames, args.orbit, png)
                load_first[mapper] = vtk[1]
                load_first[mapper + "_ms"] = vtk[0]
                load_first[mapper + "_psnr"] = psnr(png, ref_png)
                if args.ring_px:
                    print(f"    VTK {mapper} step 1: interior %.2f dB, {args.ring_px}-pixel ring %.2f dB"
                          % psnr_split(png, ref_png, args.ring_px), flush=True)
            for backend in backends:
                btag = f"{tag}_{backend}"
                # peakcast at each candidate step. Postclassified at each step, and preintegrated
                # at the same steps: both are DVR of the same TF, so both may be picked "at equal error".
                pc = []
                for method in ["post"] + ([] if args.no_preint else ["preint"]):
                    for step in ([float(x) for x in args.steps.split(",")] if args.steps else STEPS):
                        sp = work / f"{btag}_{method}_{step}.json"
                        j = scene_json(spec, volume, lo, hi, size, step)
                        if method == "preint":
                            j["render"]["classification"] = "preint"
                        sp.write_text(json.dumps(j))
                        png = work / f"{btag}_{method}_{step}.png"
                        j = peakcast_case(args.peakcast, sp, args.frames, args.orbit, png, backend)
                        pc.append(dict(method=method, step=step, ms=j["frame_ms_median"], psnr=psnr(png, ref_png),
                                       spr=j["samples_per_ray"], variant=j["variant"],
                                       load_first_ms=j["load_to_first_frame_ms"]))
                peaks_cache = {}

                def peaks_at(step):
                    if step not in peaks_cache:
                        sp = work / f"{btag}_peaks_{step}.json"
                        j = scene_json(spec, volume, lo, hi, size, step)
                        j["render"]["classification"] = "peaks"
                        sp.write_text(json.dumps(j))
                        png = work / f"{btag}_peaks_{step}.png"
                        r = peakcast_case(args.peakcast, sp, args.frames, args.orbit, png, backend)
                        peaks_cache[step] = dict(step=step, ms=r["frame_ms_median"], psnr=psnr(png, ref_png),
                                                 variant=r["variant"])
                    return peaks_cache[step]

                for mapper in ("fixed-point", "gpu"):
                    ms, q = load_first[mapper + "_ms"], load_first[mapper + "_psnr"]
                    ok = [p for p in pc if p["psnr"] >= q - 1e-9]
                    best = min(ok, key=lambda p: p["ms"]) if ok else max(pc, key=lambda p: p["psnr"])
                    # The same scene with peak finding at the chosen step: a different optical model
                    # (Knoll's peaks on top of DVR), so timed and scored but not used to pick the step.
                    pk = peaks_at(best["step"])  # at the chosen step, whichever method won
                    row = dict(scene=name, size=size, mapper=mapper, backend=backend, vtk_ms=ms, vtk_psnr=q, pc=best,
                               equal_error=bool(ok), pc_all=pc, peaks=pk)
                    rows.append(row)
                    print(f"{name:<8} {size:>5} {mapper:<11} {1.0:>5} {ms:>8.1f} {q:>6.1f} | {backend:<7} "
                          f"{best['method'][:4]}@{best['step']:<4} "
                          f"{best['ms']:>8.1f} {best['psnr']:>7.1f} {best['spr']:>6.1f} {best['ms'] / ms:>6.2f} | "
                          f"{pk['ms']:>8.1f} {pk['ms'] / ms:>6.2f}"
                          f"{'' if ok else '  (no step reaches VTK: best PSNR shown)'}", flush=True)
                pc1 = min((p for p in pc if p["method"] == "post"), key=lambda p: abs(p["step"] - 1.0))
                print(f"    load + first frame (step 1): VTK fixed-point {load_first['fixed-point']:.0f} ms, VTK GPU "
                      f"{load_first['gpu']:.0f} ms, peakcast {backend} {pc1['load_first_ms']:.0f} ms "
                      f"(volume file in the page cache)")
                rows.append(dict(scene=name, size=size, backend=backend,
                                 load_first_ms={"fixed-point": load_first["fixed-point"], "gpu": load_first["gpu"],
                                                "peakcast": pc1["load_first_ms"]}))
                for p in pc:
                    split = ""
                    if args.ring_px:
                        png = work / f"{btag}_{p['method']}_{p['step']}.png"
                        split = (", interior %.2f dB, ring %.2f dB" % psnr_split(png, ref_png, args.ring_px))
                    print(f"    peakcast {backend} {p['method']} step {p['step']}: {p['ms']:.1f} ms, {p['psnr']:.1f} dB"
                          f"{split}, {p['spr']:.1f} samples/ray, {p['variant']}", flush=True)
    (work / "peers.json").write_text(json.dumps(rows, indent=1))
    print("ratio: peakcast frame ms / VTK frame ms at equal error (the fastest peakcast candidate, post@step or "
          "prei(ntegrated)@step, whose PSNR against the converged image is >= VTK's); peaks: peakcast with peak "
          "finding at that step")
    print(f"images and peers.json in {work}")


if __name__ == "__main__":
    main()
