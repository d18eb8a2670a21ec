#!/usr/bin/env python3
"""A chunked upload far past the server's memory budget (a command, not a test: it writes about
7 GiB to disk): a `--gib` GiB uint16 numpy memmap (1024³ for 2 GiB) sent by the Python client's
upload_chunked into a `peakcast serve --memory-budget-mib 256`, which builds its pyramid; then a
still at the level held and one at full resolution (by bricks). Prints the upload's and build's
seconds and rates, the server's peak RSS (VmHWM) and the client's, and the stills' times.

Usage: scripts/bench_upload.py [--build build] [--gib 2] [--budget-mib 256] [--dir bench-data/upload]
"""
import argparse, os, pathlib, re, shutil, subprocess, sys, threading, time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "client-python"))
import peakcast  # noqa: E402


def status_mib(pid, field):
    for line in open(f"/proc/{pid}/status"):
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")


def reset_peak(pid):
    """VmHWM from now on (the kernel's clear_refs 5); False where it cannot be reset."""
    try:
        with open(f"/proc/{pid}/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


class AnonPeak(threading.Thread):
    """The client's own memory (RssAnon: the memmap's file pages it maps are not its heap), sampled."""

    def __init__(self):
        super().__init__(daemon=True)
        self.peak, self.running = 0.0, True

    def run(self):
        while self.running:
            self.peak = max(self.peak, status_mib(os.getpid(), "RssAnon"))
            time.sleep(0.05)


def make_array(path, n):
    """n³ uint16 on disk, written slab by slab: a shell and a few blobs over a gradient."""
    a = np.lib.format.open_memmap(path, "w+", np.uint16, (n, n, n))
    y, x = np.mgrid[0:n, 0:n].astype(np.float32) / n - 0.5
    for z0 in range(0, n, 32):
        z = (np.arange(z0, min(n, z0 + 32), dtype=np.float32) / n - 0.5)[:, None, None]
        r = np.sqrt(x * x + y * y + z * z)
        shell = np.exp(-((r - 0.35) / 0.02) ** 2)
        a[z0:z0 + 32] = (2000 + 50000 * shell + 8000 * (x + 0.5)).astype(np.uint16)
    a.flush()
    return a


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    ap.add_argument("--gib", type=float, default=2.0)
    ap.add_argument("--budget-mib", type=int, default=256)
    ap.add_argument("--dir", type=pathlib.Path, default=ROOT / "bench-data/upload")
    a = ap.parse_args()
    n = int(round((a.gib * (1 << 30) / 2) ** (1 / 3)))
    a.dir.mkdir(parents=True, exist_ok=True)
    uploads = a.dir.parent / (a.dir.name + "-uploads")  # never inside a --data directory
    shutil.rmtree(uploads, ignore_errors=True)
    array = make_array(a.dir / "big.npy", n)
    cmd = [str(a.build / "server/peakcast"), "serve", "--port", "0", "--data", str(a.dir), "--upload-dir", str(uploads),
           "--memory-budget-mib", str(a.budget_mib), "--max-upload-mib", str(int(a.gib * 1024) + 64),
           "--upload-budget-mib", str(int(a.gib * 1024 * 3)), "--max-still-samples", "1e12"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url = None
    log = []
    for line in proc.stdout:
        log.append(line)
        m = re.search(r"serving on (http://[\d.]+:\d+)", line)
        if m:
            url = m.group(1)
            break
    if url is None:
        raise SystemExit("the server did not start:\n" + "".join(log))
    threading.Thread(target=lambda: [None for _ in proc.stdout], daemon=True).start()
    try:
        c = peakcast.Client(url, timeout=3600)
        marks = {}

        def progress(done, total, stage):
            marks.setdefault(stage, time.perf_counter())
        c.health()
        idle = status_mib(proc.pid, "VmRSS")
        reset_peak(proc.pid)
        anon = AnonPeak()
        anon.start()
        t0 = time.perf_counter()
        vid = c.upload_chunked(array, name="big", progress=progress)
        t1 = time.perf_counter()
        anon.running = False
        upload_peak = status_mib(proc.pid, "VmHWM")
        reset_peak(proc.pid)
        sent = marks.get("building", t1) - t0
        info = c.volume(vid)
        scene = {"volume": vid, "image": {"width": 512, "height": 512}}
        t = time.perf_counter()
        held = c._http.request("POST", "/api/render?format=png&resolution=held", peakcast.client.scene_json(scene),
                               {"Content-Type": "application/json"})
        t_held = time.perf_counter() - t
        t = time.perf_counter()
        full = c.render(scene)
        t_full = time.perf_counter() - t
        gib = n ** 3 * 2 / (1 << 30)
        print(f"\n| {n}³ uint16 ({gib:.2f} GiB) into --memory-budget-mib {a.budget_mib} | value |")
        print("|---|---|")
        print(f"| chunks sent | {sent:.1f} s ({gib * 1024 / sent:.0f} MiB/s) |")
        print(f"| pyramid built | {t1 - t0 - sent:.1f} s ({info['levels']} levels, held at level {info['level']}) |")
        print(f"| server RSS idle, before the upload | {idle:.0f} MiB |")
        print(f"| server peak RSS (VmHWM), upload and build | {upload_peak:.0f} MiB |")
        print(f"| server peak RSS (VmHWM), the two stills | {status_mib(proc.pid, 'VmHWM'):.0f} MiB |")
        print(f"| client peak RssAnon (its own memory; the memmap's pages are the file's) | {anon.peak:.0f} MiB |")
        print(f"| still 512², level held | {t_held:.2f} s ({len(held[2])} bytes) |")
        print(f"| still 512², full resolution (bricks: {full.bricks}) | {t_full:.2f} s, mean {full.mean():.1f} |")
        c.delete(vid)
    finally:
        proc.terminate()
        proc.wait(60)
        os.remove(a.dir / "big.npy")
        shutil.rmtree(uploads, ignore_errors=True)


if __name__ == "__main__":
    main()
