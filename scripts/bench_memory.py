#!/usr/bin/env python3
"""bench memory: the server's host memory for a volume against its voxel bytes (issue 13).

A benchmark command, not a test. Starts `peakcast serve` twice: with a tiny volume (the
baseline: code, llvmpipe, buffers) and with VOLUME, renders one REST still on each (so the GPU
copy exists and, on llvmpipe, lives in host memory), and prints VmRSS after the load, after the
still, and the peak (VmHWM), minus the baseline, as a multiple of the volume's voxel bytes.

Usage: scripts/bench_memory.py VOLUME [--peakcast build/server/peakcast]
"""
import argparse, json, pathlib, re, subprocess, sys, tempfile, time, urllib.request

ROOT = pathlib.Path(__file__).resolve().parents[1]


def status(pid, key):
    for line in open(f"/proc/{pid}/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024
    return 0


def serve(peakcast, volume):
    proc = subprocess.Popen([peakcast, "serve", "--port", "0", "--volume", str(volume), "--data",
                             str(pathlib.Path(volume).parent)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
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


def measure(peakcast, volume):
    proc, base = serve(peakcast, volume)
    try:
        info = json.load(urllib.request.urlopen(base + "/api/volumes"))
        vol = info["volumes"][0] if isinstance(info, dict) else info[0]
        loaded = status(proc.pid, "VmRSS")
        body = json.dumps({"volume": vol["id"], "image": {"width": 256, "height": 256}}).encode()
        req = urllib.request.Request(base + "/api/render", data=body, headers={"Content-Type": "application/json"})
        urllib.request.urlopen(req, timeout=300).read()
        time.sleep(0.5)
        info = json.load(urllib.request.urlopen(base + "/api/volumes"))
        vol = info["volumes"][0] if isinstance(info, dict) else info[0]
        return dict(bytes=vol["bytes"], loaded=loaded, rendered=status(proc.pid, "VmRSS"),
                    peak=status(proc.pid, "VmHWM"), phases=vol.get("load_phases"))
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("volume")
    ap.add_argument("--peakcast", default=str(ROOT / "build/server/peakcast"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tiny = pathlib.Path(tmp) / "tiny.mhd"
        subprocess.run([a.peakcast, "make-volume", "sphere", "--dims", "8", "8", "8", "-o", tiny], check=True,
                       capture_output=True)
        base = measure(a.peakcast, tiny)
    m = measure(a.peakcast, a.volume)
    mib = 1024.0 * 1024.0
    print(f"voxel bytes: {m['bytes'] / mib:.1f} MiB; baseline server (8^3 volume, one still): "
          f"{base['rendered'] / mib:.1f} MiB")
    for key, what in (("loaded", "after load"), ("rendered", "after one still (GPU copy made)"),
                      ("peak", "peak (VmHWM)")):
        extra = m[key] - base[key]
        print(f"{what:34s} RSS {m[key] / mib:8.1f} MiB, over the baseline {extra / mib:8.1f} MiB = "
              f"{extra / m['bytes']:.2f}x the voxel bytes")
    print(f"load phases: {m['phases']}")


if __name__ == "__main__":
    sys.exit(main())
