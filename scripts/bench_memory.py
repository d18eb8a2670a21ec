#!/usr/bin/env python3
"""bench memory: the server's host memory for a volume against its voxel bytes.

A benchmark command, not a test. Starts `peakcast serve` twice: with a tiny volume (the
baseline: code, llvmpipe, buffers) and with VOLUME, renders one REST still on each (so the GPU
copy exists and, on llvmpipe, lives in host memory), and prints VmRSS after the load, after the
still, and the peak (VmHWM), minus the baseline, as a multiple of the volume's voxel bytes.

With --ranks N the servers run under `mpirun --oversubscribe -np N` and every rank's
memory is printed: no rank, the serving rank 0 included, should hold more than its brick.

Usage: scripts/bench_memory.py VOLUME [--peakcast build/server/peakcast] [--ranks N]
"""
import argparse, json, os, pathlib, re, shutil, subprocess, sys, tempfile, time, urllib.request

ROOT = pathlib.Path(__file__).resolve().parents[1]


def status(pid, key):
    for line in open(f"/proc/{pid}/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
    return 0


def rank_pids(proc):
    """{rank: pid} of the peakcast processes under mpirun `proc` ({0: proc.pid} without mpirun)."""
    children = {}
    for d in pathlib.Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(d.name))
    todo, out = [proc.pid], {}
    while todo:
        pid = todo.pop()
        todo += children.get(pid, [])
        try:
            env = pathlib.Path(f"/proc/{pid}/environ").read_bytes().decode(errors="replace").split("\0")
        except OSError:
            continue
        rank = [kv.split("=", 1)[1] for kv in env if kv.startswith("OMPI_COMM_WORLD_RANK=")]
        if rank:
            out[int(rank[0])] = pid
    return out or {0: proc.pid}


def serve(peakcast, volume, ranks):
    launcher = []
    if ranks > 1:
        launcher = [shutil.which("mpirun") or "mpirun", "--oversubscribe", "-np", str(ranks)]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    proc = subprocess.Popen([*launcher, peakcast, "serve", "--port", "0", "--volume", str(volume), "--data",
                             str(pathlib.Path(volume).parent)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env=env)
    deadline = time.time() + 120
    while time.time() < deadline:
        line = proc.stdout.readline()
        m = re.search(r"serving on http://([\d.]+):(\d+)", line)
        if m:
            return proc, f"http://{m.group(1)}:{m.group(2)}"
        if not line:
            break
    proc.kill()
    raise RuntimeError("server did not start")


def measure(peakcast, volume, ranks=1):
    proc, base = serve(peakcast, volume, ranks)
    try:
        info = json.load(urllib.request.urlopen(base + "/api/volumes"))
        vol = info["volumes"][0] if isinstance(info, dict) else info[0]
        pids = rank_pids(proc)
        loaded = {r: status(p, "VmRSS") for r, p in pids.items()}
        body = json.dumps({"volume": vol["id"], "image": {"width": 256, "height": 256}}).encode()
        req = urllib.request.Request(base + "/api/render", data=body, headers={"Content-Type": "application/json"})
        urllib.request.urlopen(req, timeout=300).read()
        time.sleep(0.5)
        info = json.load(urllib.request.urlopen(base + "/api/volumes"))
        vol = info["volumes"][0] if isinstance(info, dict) else info[0]
        return dict(bytes=vol["bytes"], loaded=loaded, rendered={r: status(p, "VmRSS") for r, p in pids.items()},
                    peak={r: status(p, "VmHWM") for r, p in pids.items()}, phases=vol.get("load_phases"),
                    resident_bytes=vol.get("resident_bytes"))
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("volume")
    ap.add_argument("--peakcast", default=str(ROOT / "build/server/peakcast"))
    ap.add_argument("--ranks", type=int, default=1, help="serve under mpirun -np N (each rank reported)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tiny = pathlib.Path(tmp) / "tiny.mhd"
        subprocess.run([a.peakcast, "make-volume", "sphere", "--dims", "8", "8", "8", "-o", tiny], check=True,
                       capture_output=True)
        base = measure(a.peakcast, tiny, a.ranks)
    m = measure(a.peakcast, a.volume, a.ranks)
    mib = 1024.0 * 1024.0
    print(f"voxel bytes: {m['bytes'] / mib:.1f} MiB; {a.ranks} rank(s); held per rank (resident_bytes): "
          f"{(m['resident_bytes'] or 0) / mib:.1f} MiB")
    for r in sorted(m["peak"]):
        print(f"rank {r}: baseline server (8^3 volume, one still) {base['rendered'].get(r, 0) / mib:.1f} MiB")
        for key, what in (("loaded", "after load"), ("rendered", "after one still (GPU copy made)"),
                          ("peak", "peak (VmHWM)")):
            extra = m[key][r] - base[key].get(r, 0)
            print(f"  {what:34s} RSS {m[key][r] / mib:8.1f} MiB, over the baseline {extra / mib:8.1f} MiB = "
                  f"{extra / m['bytes']:.2f}x the voxel bytes")
    print(f"load phases: {m['phases']}")


if __name__ == "__main__":
    sys.exit(main())
