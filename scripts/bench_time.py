#!/usr/bin/python3
"""Stepping through a time series in a viewer (a benchmark command, not a test): a 20-point series
of 256³ uint16 volumes (scripts/make_time_series.py) served by `peakcast serve` on one backend; a
WebSocket viewer at 512² steps t = 0, 1, ..., 19 and waits for each time point's final frame:
first with nothing held (each step reads its time point, or finds it read ahead), then again with
them held. Prints time points per second, and the order the frames came in. Then `--play-rate`
points a second for 4 s as the client's play does (a step only once the last asked for is drawn,
skipping by the clock): how many were shown, and whether any came out of order.

Usage: scripts/bench_time.py [--build build] [--backend cpu] [--size 512] [--times 20] [--n 256]
       [--play-rate 10] [--data-dir bench-data/time]"""
import argparse, asyncio, os, pathlib, sys, time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests/net"))
sys.path.insert(0, str(ROOT / "scripts"))
import make_time_series  # noqa: E402


async def final_at(c, t):
    while True:
        f = await c.next_frame(final=True, timeout=120)
        st = await c.stats_of(f)
        if st.get("time") == t:
            return st


async def run(server, a, harness):
    c = await harness.Client.connect(server)
    tf = {"points": [[0, 0, 0, 0, 0], [12000, 0.2, 0.8, 1, 0.02], [50000, 1, 0.8, 0.2, 0.5]]}
    await c.hello(a.size, a.size, volume="series.zarr", state={"tf": tf})
    await final_at(c, 0)
    for label in ("first pass (read now or read ahead)", "second pass (held)"):
        t0 = time.perf_counter()
        order = []
        for t in list(range(1, a.times)) + [0]:
            await c.send({"type": "time", "time": t})
            order.append((await final_at(c, t))["time"])
        dt = time.perf_counter() - t0
        print(f"{label}: {a.times} time points in {dt:.2f} s = {a.times / dt:.2f} time points/s; order {order}")
    # Playing: the client's rule (time-controls.js) at --play-rate.
    shown, widths, asked, start, last = [], [], None, time.perf_counter(), 0
    while time.perf_counter() - start < 4.0:
        want = int((time.perf_counter() - start) * a.play_rate) % a.times
        if asked is None and want != last:
            asked = want
            await c.send({"type": "time", "time": want})
        try:
            m = await c.recv(0.02)
        except asyncio.TimeoutError:
            continue
        if isinstance(m, dict) and m.get("type") == "stats" and "time" in m:
            if not shown or shown[-1] != m["time"]:
                shown.append(m["time"])
                widths.append(m["width"])
            if m["time"] == asked:
                last, asked = asked, None
    backwards = sum(1 for x, y in zip(shown, shown[1:]) if y < x and not (x == a.times - 1 or y == 0))
    widths.sort()
    print(f"playing at {a.play_rate}/s for 4 s: {len(shown)} time points shown ({len(shown) / 4:.1f}/s), "
          f"{backwards} out of order, frames {widths[len(widths) // 2] if widths else 0} px wide (median; "
          f"interactive frames shrink to the frame budget as in an orbit): {shown}")
    await c.close()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", type=pathlib.Path, default=ROOT / "build")
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--times", type=int, default=20)
    ap.add_argument("--n", type=int, default=256)
    ap.add_argument("--play-rate", type=float, default=10)
    ap.add_argument("--data-dir", type=pathlib.Path, default=ROOT / "bench-data/time")
    a = ap.parse_args()
    series = a.data_dir / "series.zarr"
    if not (series / ".zattrs").exists():
        a.data_dir.mkdir(parents=True, exist_ok=True)
        make_time_series.write(series, times=a.times, n=a.n)
    os.environ["PEAKCAST_BIN"] = str(a.build / "server/peakcast")
    os.environ["PEAKCAST_BACKEND"] = a.backend
    import harness  # after PEAKCAST_BIN
    with harness.Server("--data", str(a.data_dir), volumes=()) as s:
        asyncio.run(run(s, a, harness))


if __name__ == "__main__":
    main()
