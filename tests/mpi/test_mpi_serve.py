#!/usr/bin/env python3
"""Label mpi: `mpirun -np 2 peakcast serve` (rank 0 serves, both ranks render their
bricks, IceT composites) against the one-process server: health and /metrics show the ranks, a
REST still equals `peakcast render`, a viewer's stream (interactive frames, then a lossless
final frame) equals the one-process server's, a scene bricks cannot draw is refused and the
job goes on, and SIGTERM stops every rank. No rank holds a whole volume: the serving rank reads
its brick like the others, and the volume's range, histogram and NaN/Inf count are reduced from the
bricks (equal to one process's)."""
import asyncio, gzip, json, os, pathlib, shutil, subprocess, sys, time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "net"))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from harness import Client, Server, http, decode_image  # noqa: E402
from PIL import Image as PILImage  # noqa: E402
import nonfinite_volume  # noqa: E402
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "scripts"))
import bench_memory  # noqa: E402  (each rank's memory under mpirun, as `bench memory --ranks` reads it)
import make_time_series  # noqa: E402

PEAKCAST = os.environ["PEAKCAST_BIN"]
MPIRUN = os.environ.get("MPIEXEC", shutil.which("mpirun") or "mpirun")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
           OMPI_MCA_rmaps_base_oversubscribe="1")
ENV.pop("PEAKCAST_BACKEND", None)
CAMERA = {"eye": [75, -160, 230], "center": [75, 75, 75], "up": [0, 0, 1], "fov_y": 30}
TF = {"points": [[0, 0.1, 0.3, 1, 0], [80, 0.2, 0.5, 1, 0.05], [150, 1, 0.6, 0.2, 0.6], [255, 1, 1, 1, 0.9]]}
# Rays run until opaque on bricks; the one-process server is asked the same.
RENDER = {"classification": "preint", "step": 1, "early_termination": 1.0}


def max_level_diff(a, b):
    a, b = a.convert("RGB").tobytes(), b.convert("RGB").tobytes()
    assert len(a) == len(b)
    return max(abs(x - y) for x, y in zip(a, b))


async def stream(server):
    """hello, a lossless final, a drag (interactive frames), the final after it."""
    c = await Client.connect(server)
    await c.hello(200, 150, state={"camera": CAMERA, "tf": TF, "render": RENDER})
    await c.send({"type": "quality", "final_format": "png"})
    await c.next_frame(final=True)
    interactive = 0
    cam = dict(CAMERA)
    for i in range(6):
        cam = dict(cam, eye=[75 + 15 * i, -160, 230])
        await c.send({"type": "camera", "camera": cam})
        f = await c.next_frame()
        interactive += not f["final"]
    final = await c.next_frame(final=True)
    while not final["png"] or final["camera_version"] < 7:
        final = await c.next_frame(final=True)
    await c.close()
    return interactive, decode_image(final["image"])


async def paint(server):
    """A session with a ray texture: a lossless final, then strokes on each channel, each
    acknowledged, and the final after the last (the workers get each stroke once)."""
    c = await Client.connect(server)
    await c.hello(200, 150, state={"camera": CAMERA, "tf": TF,
                                   "render": dict(RENDER, ray_texture={"mapping": "view", "size": [48, 48]})})
    await c.send({"type": "quality", "final_format": "png"})
    await c.next_frame(final=True)
    strokes = [{"channel": "termination", "center": [0.45, 0.5], "radius": 0.3, "falloff": 0.5, "value": 0.2},
               {"channel": "step", "center": [0.6, 0.4], "radius": 0.25, "value": 3},
               {"channel": "blend", "center": [0.3, 0.6], "radius": 0.2, "value": 0.7}]
    for seq, st in enumerate(strokes, 1):
        await c.send({"type": "stroke", "seq": seq, "stroke": st})
        ack = await c.next_text("stroke_ack")
        assert ack["seq"] == seq and ack["strokes"] == seq, ack
        final = await c.next_frame(final=True)
        while not final["png"]:
            final = await c.next_frame(final=True)
    await asyncio.sleep(0.5)  # a final frame still queued after the last stroke's
    c.texts.clear()
    await c.send({"type": "quality", "final_format": "png"})
    final = await c.next_frame(final=True)
    while not final["png"]:
        final = await c.next_frame(final=True)
    await c.close()
    return decode_image(final["image"])


def still_against_one_process(srv, scene, volume_path, tmp, tag, backend="cpu"):
    """POSTs `scene` to the distributed server and renders it with `peakcast render` in one
    process (the volume at volume_path): (status, X-Variant, the comparison's JSON)."""
    status, headers, png = http(srv, "/api/render", "POST", json.dumps(scene).encode())
    (tmp / f"{tag}_mpi.png").write_bytes(png)
    (tmp / f"{tag}.json").write_text(json.dumps(dict(scene, volume=str(volume_path))))
    subprocess.run([PEAKCAST, "render", tmp / f"{tag}.json", "-o", tmp / f"{tag}_one.png", "--backend", backend],
                   check=True, capture_output=True, env=ENV)
    cmp = json.loads(subprocess.run([PEAKCAST, "compare", tmp / f"{tag}_one.png", tmp / f"{tag}_mpi.png"], check=True,
                                    capture_output=True, text=True).stdout)
    return status, headers.get("X-Variant", ""), cmp


DATA = pathlib.Path(__file__).resolve().parents[1] / "data"


def gl_ranks_check(tmp):
    """mpirun serve --backend gl: every rank draws its brick with the GL ray caster (one GPU per
    rank; llvmpipe here); a REST still equals `peakcast render --backend gl` within 1/255."""
    srv = Server("--backend", "gl", launcher=[MPIRUN, "--oversubscribe", "-np", "2"], env=ENV)
    try:
        scene = {"volume": "heptane_151.nrrd", "image": {"width": 120, "height": 90}, "camera": CAMERA, "tf": TF,
                 "render": RENDER, "background": [0.1, 0.1, 0.2]}
        status, variant, cmp = still_against_one_process(srv, scene, DATA / "heptane_151.nrrd", tmp, "gl", "gl")
        # A probe needs the voxels, which the serving rank does not hold: refused by name.
        pstatus, _, pbody = http(srv, "/api/probe", "POST", json.dumps(dict(scene, pixel=[60, 45])).encode())
        # So does a depth image (the probe's rule per pixel); the float image is composited as the PNG is.
        dstatus, _, dbody = http(srv, "/api/render?format=depth", "POST", json.dumps(scene).encode())
        fstatus, fheaders, fbody = http(srv, "/api/render?format=float", "POST", json.dumps(scene).encode())
        return ("GL ranks: a REST still equals peakcast render --backend gl within 1/255; a probe and a depth "
                "image get 422; the float image composites",
                status == 200 and "brick" in variant and "2ranks" in variant and cmp["max_abs"] <= 1 / 255 + 1e-6
                and pstatus == 422 and b"not_supported" in pbody and dstatus == 422 and b"not_supported" in dbody
                and fstatus == 200 and len(fbody) == 120 * 90 * 16 and fheaders.get("X-Width") == "120",
                (status, variant, cmp, pstatus, pbody[:200], dstatus, dbody[:200], fstatus, len(fbody)))
    finally:
        srv.stop()


def scene_small():
    return {"volume": "heptane_151.nrrd", "image": {"width": 48, "height": 40}, "camera": CAMERA, "tf": TF}


# What /api/volumes/ID reports that must not depend on the rank count (load times may).
INFO_KEYS = ("dims", "dtype", "spacing", "origin", "range", "bytes", "histogram", "nonfinite_replaced")


def volume_infos(srv, volumes):
    """Each (file, id) loaded by a small still, then its /api/volumes entry (with the histogram)."""
    out = {}
    for name, vid in volumes:
        status, _, body = http(srv, "/api/render", "POST",
                               json.dumps({"volume": name, "image": {"width": 32, "height": 32}}).encode())
        assert status == 200, (name, status, body[:300])
        status, _, body = http(srv, "/api/volumes/" + vid)
        assert status == 200, (vid, status, body[:300])
        out[vid] = json.loads(body)
    return out


def rank_peak_kib(srv):
    """{rank: VmHWM in KiB} of the processes mpirun started for `srv`."""
    return {r: bench_memory.status(pid, "VmHWM") // 1024 for r, pid in bench_memory.rank_pids(srv.proc).items()}


def write_big_u16(path, dims=(256, 256, 512)):
    """Random uint16 voxels: 64 MiB, large next to a rank's own memory."""
    nx, ny, nz = dims
    path.write_bytes(f"NRRD0004\ntype: uint16\ndimension: 3\nsizes: {nx} {ny} {nz}\nencoding: raw\n"
                     "endian: little\n\n".encode() + os.urandom(2 * nx * ny * nz))
    return 2 * nx * ny * nz


def three_ranks_check(tmp, data_dir, one_infos, volumes):
    """mpirun -np 3 serve (uneven split, oversubscribed): the volumes' info reduced over three
    bricks equals one process's, and a REST still equals `peakcast render`."""
    srv = Server("--data", str(data_dir), launcher=[MPIRUN, "--oversubscribe", "-np", "3"], env=ENV)
    try:
        infos = volume_infos(srv, volumes)
        differ = {vid: [k for k in INFO_KEYS if infos[vid].get(k) != one_infos[vid].get(k)] for vid in infos}
        scene = {"volume": "heptane_151.nrrd", "image": {"width": 120, "height": 90}, "camera": CAMERA, "tf": TF,
                 "render": RENDER, "background": [0.1, 0.1, 0.2]}
        status, variant, cmp = still_against_one_process(srv, scene, DATA / "heptane_151.nrrd", tmp, "three")
        return ("3 ranks: volume info equals one process's, a REST still equals peakcast render within 1/255",
                not any(differ.values()) and status == 200 and "3ranks" in variant and cmp["max_abs"] <= 1 / 255 + 1e-6,
                (differ, status, variant, cmp))
    finally:
        srv.stop()


def mixed_backends_check():
    """Ranks on different backends (MPMD: rank 0 on the CPU backend, rank 1 on GL) are refused by
    name and the job ends, rather than drawing seams at brick faces."""
    data = str(DATA)
    cmd = [MPIRUN, "--oversubscribe", "-np", "1", PEAKCAST, "serve", "--port", "0", "--data", data, "--backend", "cpu",
           ":", "-np", "1", PEAKCAST, "serve", "--port", "0", "--data", data, "--backend", "gl"]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=60, env=ENV)
    except subprocess.TimeoutExpired:
        return ("ranks on different backends end the job", False, "still running after 60 s")
    return ("ranks on different backends end the job, naming the mismatch",
            r.returncode != 0 and "every rank needs the same" in r.stdout + r.stderr, (r.returncode, r.stderr[-400:]))


def main():
    failed = 0
    # A multi-page TIFF: one process serves it, bricks cannot read a region of it.
    tiff_dir = pathlib.Path(os.environ.get("TMPDIR", "/tmp")) / f"peakcast-mpi-tiff-{os.getpid()}"
    tiff_dir.mkdir(exist_ok=True)
    pages = [PILImage.new("L", (8, 8), 40 * k) for k in range(4)]
    pages[0].save(tiff_dir / "stack.tif", save_all=True, append_images=pages[1:])
    nonfinite_volume.write(tiff_dir / "nonfinite.nrrd")
    # uint8, uint16 (MetaImage), float with NaN/Inf in different bricks
    volumes = [("heptane_151.nrrd", "heptane_151"), ("HeadMRVolume.mhd", "HeadMRVolume.mhd"),
               ("nonfinite.nrrd", "nonfinite.nrrd")]
    one = Server("--backend", "cpu", "--data", str(tiff_dir), env=ENV)
    try:
        _, one_final = asyncio.run(stream(one))
        one_painted = asyncio.run(paint(one))
        one_infos = volume_infos(one, volumes)
    finally:
        one.stop()
    srv = Server("--data", str(tiff_dir), launcher=[MPIRUN, "--oversubscribe", "-np", "2"], env=ENV)
    try:
        checks = []
        infos = volume_infos(srv, volumes)
        differ = {vid: [k for k in INFO_KEYS if infos[vid].get(k) != one_infos[vid].get(k)] for vid in infos}
        checks.append(("each volume's range, histogram and NaN/Inf count, reduced from the bricks, equal one process's",
                       not any(differ.values()), differ))
        before = rank_peak_kib(srv)
        big_bytes = write_big_u16(tiff_dir / "big.nrrd")
        big = volume_infos(srv, [("big.nrrd", "big.nrrd")])["big.nrrd"]
        peaks = rank_peak_kib(srv)
        growth = {r: (peaks[r] - before.get(r, 0)) * 1024 for r in peaks}
        print(f"  64 MiB volume on 2 ranks: peak memory grew by rank 0 {growth.get(0, 0) / 2**20:.0f} MiB, "
              f"rank 1 {growth.get(1, 0) / 2**20:.0f} MiB; resident_bytes {big['resident_bytes'] / 2**20:.1f} MiB",
              flush=True)
        # A brick is half the volume plus ghosts; reading it whole anywhere adds the volume.
        checks.append(("no rank, the serving one included, holds the whole volume: each rank's peak memory grows by "
                       "less than 3/4 of it, and the budget counts one brick",
                       sorted(growth) == [0, 1] and all(g < big_bytes * 0.75 for g in growth.values())
                       and big_bytes * 0.5 <= big["resident_bytes"] < big_bytes * 0.6, (growth, big["resident_bytes"])))
        # A gzip stream cut at 3/4: the header and the lower brick read, the upper brick's rank
        # fails; every rank agrees, the request is refused, and the job goes on.
        raw = os.urandom(16 * 16 * 64)
        packed = gzip.compress(raw)
        (tiff_dir / "cut.nrrd").write_bytes(b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 16 16 64\nencoding: gzip\n\n"
                                            + packed[:len(packed) * 3 // 4])
        status, _, body = http(srv, "/api/render", "POST",
                               json.dumps({"volume": "cut.nrrd", "image": {"width": 32, "height": 32}}).encode())
        status2, _, _ = http(srv, "/api/render", "POST", json.dumps(scene_small()).encode())
        checks.append(("a file one rank cannot read (a cut gzip stream) is refused by name, and the job goes on",
                       400 <= status < 500 and b"cannot be read as bricks" in body and status2 == 200 and srv.alive(),
                       (status, body[:300], status2)))
        status, _, body = http(srv, "/api/health")
        health = json.loads(body)
        checks.append(("health shows 2 ranks", status == 200 and health["ranks"] == 2 and "2 ranks" in health["gl_renderer"],
                       health))
        _, _, metrics = http(srv, "/metrics")
        checks.append(("/metrics shows the ranks", "peakcast_ranks 2" in metrics.decode(), ""))

        scene = {"volume": "heptane_151.nrrd", "image": {"width": 160, "height": 120}, "camera": CAMERA, "tf": TF,
                 "render": RENDER, "background": [0.1, 0.1, 0.2]}
        tmp = pathlib.Path(os.environ.get("TMPDIR", "/tmp")) / f"peakcast-mpi-serve-{os.getpid()}"
        tmp.mkdir(exist_ok=True)
        status, variant, cmp = still_against_one_process(srv, scene, DATA / "heptane_151.nrrd", tmp, "still")
        checks.append(("REST still equals peakcast render within 1/255",
                       status == 200 and "2ranks" in variant and cmp["max_abs"] <= 1 / 255 + 1e-6,
                       (status, variant, cmp)))

        nf = {"volume": "nonfinite.nrrd", "image": {"width": 96, "height": 80}, "camera": nonfinite_volume.CAMERA,
              "tf": {"points": nonfinite_volume.TF}, "render": {"step": 1}}
        status, _, cmp = still_against_one_process(srv, nf, tiff_dir / "nonfinite.nrrd", tmp, "nf")
        checks.append(("NaN/Inf voxels take the whole volume's extremes on every rank (REST still = one process)",
                       status == 200 and cmp["max_abs"] <= 1 / 255 + 1e-6, (status, cmp)))

        # A time series: every rank reads its brick of the time point asked (not the first one).
        make_time_series.write(tiff_dir / "ball.zarr", times=4, n=32)
        ball = {"volume": "ball.zarr", "time": 3, "image": {"width": 64, "height": 48}, "render": dict(RENDER, step=0.5),
                "tf": {"points": [[0, 0, 0, 0, 0], [20000, 0.2, 0.5, 1, 0.05], [50000, 1, 0.6, 0.2, 0.8],
                                  [65535, 1, 1, 1, 1]]}}
        status, _, cmp = still_against_one_process(srv, ball, tiff_dir / "ball.zarr", tmp, "ball3")
        status0, _, cmp0 = still_against_one_process(srv, dict(ball, time=0), tiff_dir / "ball.zarr", tmp, "ball0")
        moved = json.loads(subprocess.run([PEAKCAST, "compare", tmp / "ball3_mpi.png", tmp / "ball0_mpi.png"], check=True,
                                          capture_output=True, text=True).stdout)["max_abs"]
        _, _, body = http(srv, "/api/volumes/ball.zarr")
        times = json.loads(body).get("times")
        checks.append(("a time series: the still of time point 3 (and of 0) equals one process's, they differ, and "
                       "the volume lists 4 time points",
                       status == status0 == 200 and cmp["max_abs"] <= 1 / 255 + 1e-6 and
                       cmp0["max_abs"] <= 1 / 255 + 1e-6 and moved > 0.1 and times == 4, (status, cmp, cmp0, moved, times)))

        interactive, mpi_final = asyncio.run(stream(srv))
        diff = max_level_diff(one_final, mpi_final)
        checks.append(("the stream: interactive frames, then a final equal to the one-process server's (<= 1 level)",
                       interactive > 0 and diff <= 1, (interactive, diff)))

        vs = dict(scene, render=dict(RENDER, virtual_samples=3, adaptive=True))
        status, variant, cmp = still_against_one_process(srv, vs, DATA / "heptane_151.nrrd", tmp, "vs")
        checks.append(("virtual samples with adaptive sampling: REST still equals peakcast render within 1/255",
                       status == 200 and "2ranks" in variant and cmp["max_abs"] <= 1 / 255 + 1e-6,
                       (status, variant, cmp)))
        rt = dict(scene, render=dict(RENDER, ray_texture={"mapping": "volume", "size": [32, 32], "strokes": [
            {"channel": "termination", "center": [0.5, 0.4], "radius": 0.4, "value": 0.3},
            {"channel": "step", "center": [0.4, 0.5], "radius": 0.3, "value": 2}]}))
        status, variant, cmp = still_against_one_process(srv, rt, DATA / "heptane_151.nrrd", tmp, "rt")
        checks.append(("a ray texture (termination, step): REST still equals peakcast render within 1/255",
                       status == 200 and "2ranks" in variant and cmp["max_abs"] <= 1 / 255 + 1e-6,
                       (status, variant, cmp)))
        diff = max_level_diff(one_painted, asyncio.run(paint(srv)))
        checks.append(("a viewer painting a ray texture stroke by stroke sees the one-process server's final (<= 1 level)",
                       diff <= 1, diff))
        tiff = dict(scene, volume="stack.tif", camera=None)
        tiff.pop("camera")
        status, _, body = http(srv, "/api/render", "POST", json.dumps(tiff).encode())
        status2, _, _ = http(srv, "/api/render", "POST", json.dumps(scene).encode())
        checks.append(("a TIFF stack is refused before any rank is asked, and the job goes on",
                       status >= 400 and b"TIFF" in body and status2 == 200 and srv.alive(), (status, body[:300])))
        checks.append(gl_ranks_check(tmp))
        checks.append(three_ranks_check(tmp, tiff_dir, one_infos, volumes))
        checks.append(mixed_backends_check())
        shutil.rmtree(tmp, ignore_errors=True)
        shutil.rmtree(tiff_dir, ignore_errors=True)
        for name, ok, detail in checks:
            print(f"{'ok  ' if ok else 'FAIL'} {name}" + ("" if ok else f": {detail}"), flush=True)
            failed += not ok
    finally:
        t0 = time.time()
        code = srv.stop()
        stopped = time.time() - t0
    # mpirun forwards SIGTERM to every rank: rank 0 shuts the server down ("peakcast: stopped")
    # and tells the workers to stop; mpirun returns once all have exited (its own status is 1
    # after a SIGTERM on OpenMPI 4 even when every rank exited 0).
    ok = code is not None and stopped < 10 and "peakcast: stopped" in "".join(srv.log)
    print(f"{'ok  ' if ok else 'FAIL'} SIGTERM stops every rank: mpirun exited {code} after {stopped:.1f} s", flush=True)
    failed += not ok
    print(f"{len(checks) + 1 - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
