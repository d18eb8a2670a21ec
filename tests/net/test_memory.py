#!/usr/bin/env python3
"""Memory over many sessions: 1000 WebSocket sessions opened (hello, welcome,
a first frame, a TF and a render-settings change) and closed, 10 at a time; the server's RSS at
the end is within 5% of what it was after the first 100 (the warm-up: shader variants, encoder
pools, allocator arenas). Under a sanitizer the RSS bound is not asserted (quarantine and shadow
memory grow by design). The leak checker sees the same layers in tests/net/session_leak_test.cpp
(1000 sessions without GL, unit label, run under ASan with detect_leaks=1): Mesa's own
allocations, some made from JIT code with no stack to suppress, keep LSan off for this one."""
import asyncio, json, os, pathlib, sys, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

SESSIONS = 1000
AT_ONCE = 10
WARMUP = 100
SANITIZED = os.environ.get("PEAKCAST_SANITIZER", "none") != "none"


async def one_session(i):
    c = await Client.connect(SERVER)
    await c.hello(96, 64)
    await c.next_frame()
    await c.send({"type": "tf", "version": 2 + i, "tf": {"points": [[0, 0, 0, 0, 0], [40 + i % 100, 1, 0.5, 0.2, 0.3], [255, 1, 1, 1, 0.6]]}})
    await c.send({"type": "render", "render": {"shading": i % 2 == 0}})
    await c.close()


async def test_1000_sessions_leave_rss_where_it_was():
    t0 = time.time()
    rss = {}
    for start in range(0, SESSIONS, AT_ONCE):
        await asyncio.gather(*(one_session(start + k) for k in range(AT_ONCE)))
        done = start + AT_ONCE
        if done in (WARMUP, SESSIONS):
            await asyncio.sleep(0.5)  # the last closes reach the server
            rss[done] = SERVER.rss_kib()
    health = json.loads(http(SERVER, "/api/health")[2])
    growth = rss[SESSIONS] / rss[WARMUP] - 1
    print(f"  {SESSIONS} sessions in {time.time() - t0:.0f} s; RSS after {WARMUP}: {rss[WARMUP]} KiB, "
          f"after {SESSIONS}: {rss[SESSIONS]} KiB ({growth * 100:+.1f}%); sessions left {health['sessions']}")
    assert health["sessions"] == 0, health
    if not SANITIZED:
        assert growth < 0.05, f"RSS grew {growth * 100:.1f}% over {SESSIONS - WARMUP} sessions"


if __name__ == "__main__":
    with Server("--max-sessions", "64") as SERVER:
        run_tests([test_1000_sessions_leave_rss_where_it_was])
