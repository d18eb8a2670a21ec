#!/usr/bin/env python3
"""Slow and hostile clients: each is bounded by a named limit in server/session/limits.h
and none moves a normal viewer's frame rate by more than half (stated bound: the viewer keeps at
least MIN_SHARE of its frame rate measured alone in the same run)."""
import asyncio, base64, json, multiprocessing, os, pathlib, queue, resource, socket, struct, sys, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

MIN_SHARE = 0.5
ATTACKER = "127.0.0.2"  # another loopback address: a different client host for the per-address cap


def raw_ws(server, source=ATTACKER):
    """A WebSocket opened by hand, so the test controls every byte (and how slowly it reads)."""
    s = socket.socket()
    s.bind((source, 0))
    s.settimeout(30)
    s.connect((server.host, server.port))
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall((f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
    head = b""
    while b"\r\n\r\n" not in head:
        head += s.recv(1)
    assert b" 101 " in head.split(b"\r\n")[0], head
    return s


def ws_frame(payload, opcode=1, length=None):
    """A masked client frame; `length` may lie about the payload size."""
    n = len(payload) if length is None else length
    if n < 126:
        head = struct.pack("!BB", 0x80 | opcode, 0x80 | n)
    elif n < 65536:
        head = struct.pack("!BBH", 0x80 | opcode, 0x80 | 126, n)
    else:
        head = struct.pack("!BBQ", 0x80 | opcode, 0x80 | 127, n)
    mask = os.urandom(4)
    return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


HELLO = json.dumps({"type": "hello", "viewport": {"width": 512, "height": 512}}).encode()


async def viewer_fps(server, seconds=3.0):
    """A normal viewer orbiting at 30 Hz: frames received per second."""
    c = await Client.connect(server)
    w = await c.hello(256, 256)
    cam = w["state"]["camera"]
    await c.next_frame()
    n, t0, k = 0, time.time(), 0
    while time.time() - t0 < seconds:
        k += 1
        cam = dict(cam, eye=[cam["eye"][0] + 0.5, cam["eye"][1], cam["eye"][2]])
        await c.send({"type": "camera", "camera": cam})
        try:
            while True:
                m = await c.recv(1 / 30)
                if "image" in m:
                    n += 1
        except asyncio.TimeoutError:
            pass
    await c.close()
    return n / (time.time() - t0)


def _run_hostile(hostile, stop, results):
    """The hostile client's process: runs it and hands back what it found (its error, if any)."""
    result = {}
    try:
        hostile(stop, result)
    except BaseException as e:  # noqa: B902 - the parent reports it
        result["error"] = repr(e)
    results.put(result)


def measure(server, name, hostile):
    """The viewer's frame rate while `hostile` (a thread) runs, against alone: alone is the mean of
    a measurement before and one after (A-B-A), so a machine that speeds up or slows down during
    the test does not read as the hostile client's doing. One alone window read 23.5 fps in a TSan
    run where the others read 9-19 (seen in CI): one window is not a baseline."""
    alone_before = asyncio.run(viewer_fps(server))
    # The hostile client runs in its own process, as it would on its own host. As a thread of this
    # process it shared the interpreter lock with the viewer: a ping loop that never slept held the
    # viewer to 42% of its frame rate in one CI run (TSan), a measure of Python, not of the server.
    ctx = multiprocessing.get_context("fork")
    stop, results = ctx.Event(), ctx.Queue()
    t = ctx.Process(target=_run_hostile, args=(hostile, stop, results), daemon=True)
    t.start()
    time.sleep(0.3)
    during = asyncio.run(viewer_fps(server))
    stop.set()
    # A hostile client may take a while to wind down on a loaded machine (the ping client drains
    # thousands of buffered pongs at the server's paced rate): 30 s was too short once in CI, with
    # the browser tests beside it, and left `result` empty.
    try:
        result = results.get(timeout=120)
    except queue.Empty:
        t.kill()
        raise AssertionError(f"{name}: the hostile client did not finish within 120 s")
    t.join(10)
    alone_after = asyncio.run(viewer_fps(server))
    alone = (alone_before + alone_after) / 2
    share = during / alone if alone else 0
    print(f"  {name:<28} alone {alone_before:5.1f}/{alone_after:5.1f} fps, during {during:5.1f} fps "
          f"({share:.0%}) {result}")
    assert server.alive(), "the server died"
    assert "error" not in result, f"{name}: the hostile client failed: {result['error']}"
    assert share >= MIN_SHARE, f"{name}: the viewer kept only {share:.0%} of its frame rate"
    return result


def test_slow_reader_is_bounded():
    def slow(stop, result):
        s = raw_ws(SERVER)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        s.sendall(ws_frame(HELLO))
        got, t0 = 0, time.time()
        while not stop.is_set():
            try:
                b = s.recv(1)  # 1 byte/s
            except OSError:
                break
            if not b:
                break
            got += 1
            time.sleep(1.0)
        result["bytes_read"] = got
        s.close()
    measure(SERVER, "reader at 1 byte/s", slow)


def test_1000_connections_are_capped_per_address():
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (min(hard, 4096), hard))

    def flood(stop, result):
        socks = []
        for _ in range(1000):
            s = socket.socket()
            s.bind((ATTACKER, 0))
            s.settimeout(2)
            try:
                s.connect((SERVER.host, SERVER.port))
                socks.append(s)
            except OSError:
                s.close()
        # The server keeps at most kMaxConnectionsPerAddress of them; the others are closed at once.
        time.sleep(0.5)
        open_ = 0
        for s in socks:
            s.setblocking(False)
            try:
                open_ += s.recv(1) != b""
            except BlockingIOError:
                open_ += 1
            except OSError:
                pass
        result["held_open"] = open_
        stop.wait(10)
        for s in socks:
            s.close()
    r = measure(SERVER, "1000 connections", flood)
    assert r["held_open"] <= 32, r


def test_1_gb_frame_header_is_refused_unread():
    def huge(stop, result):
        s = raw_ws(SERVER)
        s.sendall(ws_frame(b"", length=1 << 30)[:14])  # the header alone: 1 GiB promised
        s.settimeout(5)
        data = b""
        try:
            while True:
                b = s.recv(4096)
                if not b:
                    break
                data += b
        except OSError:
            pass
        # The server answers with a close frame 1009 (message too big) and hangs up.
        result["close_code"] = struct.unpack("!H", data[2:4])[0] if len(data) >= 4 and data[0] == 0x88 else None
        stop.wait()
    rss0 = SERVER.rss_kib()
    r = measure(SERVER, "1 GiB frame header", huge)
    assert r["close_code"] == 1009, r
    assert SERVER.rss_kib() - rss0 < 200 * 1024, "no allocation for the promised size"


# kMaxMessagesPerSecond and kMessageBurst (server/session/limits.h): how fast the server reads
# one client's messages.
MAX_MESSAGES_PER_SECOND, MESSAGE_BURST = 250, 500


def test_ping_only_client_is_paced():
    """A client that floods pings and never reads is either closed (1008, too slow: its unread
    pongs filled the queue) or held to the paced read rate (TCP backpressure: its sends block),
    and the viewer beside it keeps its frame rate. The client's own phases are bounded, so a
    loaded machine cannot keep it busy: 4 s of sending (a send the server does not take within
    1 s ends it), then at most 15 s of reading what was answered."""
    def pings(stop, result):
        async def run():
            c = await Client.connect(SERVER)
            n, t0, blocked = 0, time.time(), False
            try:
                while not stop.is_set() and time.time() - t0 < 4:
                    try:
                        await asyncio.wait_for(c.send({"type": "ping", "id": str(n)}), 1.0)
                    except asyncio.TimeoutError:
                        blocked = True  # backpressure: the server reads this client no faster
                        break
                    n += 1
                    if n % 50 == 0:
                        await asyncio.sleep(0.005)  # still ~30x the paced rate, without a core of its own
            except websockets.exceptions.ConnectionClosed:
                pass  # closed while sending: the drain below reads the close code
            code = None
            t1 = time.time()
            try:
                while time.time() - t1 < 15:
                    await c.recv(2)
            except asyncio.TimeoutError:
                pass
            except websockets.exceptions.ConnectionClosed as e:
                code = e.rcvd.code if e.rcvd else None
            result.update(sent=n, pongs=len([t for t in c.texts if t["type"] == "pong"]), close=code,
                          blocked=blocked, seconds=round(time.time() - t0, 1))
            c.ws.transport.abort()
        asyncio.run(run())
    r = measure(SERVER, "pings only, never reading", pings)
    assert r["pongs"] > 0, r
    # Closed as too slow, or answered no faster than the server reads (with a margin for timing).
    paced = r["pongs"] <= MESSAGE_BURST + 1.2 * MAX_MESSAGES_PER_SECOND * r["seconds"] + 50
    assert r["close"] == 1008 or paced, r


def test_10000_tf_edits_per_second_are_paced():
    def edits(stop, result):
        async def run():
            c = await Client.connect(SERVER)
            await c.hello(64, 64)
            n, t0 = 0, time.time()
            while not stop.is_set() and time.time() - t0 < 4:
                for _ in range(100):
                    v = 50 + (n % 100)
                    await c.send({"type": "tf", "tf": {"points": [[0, 0, 0, 0, 0], [v, 1, 0.5, 0.2, 0.5], [255, 1, 1, 1, 0]]}})
                    n += 1
                await asyncio.sleep(0.01)
            result["sent_per_s"] = round(n / (time.time() - t0))
            c.ws.transport.abort()  # not a polite close: the server would read the backlog first
        asyncio.run(run())
    r = measure(SERVER, "10,000 TF edits per second", edits)
    paced = float(re.search(r"peakcast_ws_paced_total ([0-9.e+]+)", http(SERVER, "/metrics")[2].decode()).group(1))
    assert paced > 0, "the message rate limit never applied"


def test_slowloris_is_cut_by_the_request_timeout():
    def trickle(stop, result):
        s = socket.socket()
        s.bind((ATTACKER, 0))
        s.connect((SERVER.host, SERVER.port))
        t0 = time.time()
        request = b"GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 200
        closed_after = None
        for b in request:
            try:
                s.sendall(bytes([b]))
                s.settimeout(0.5)
                if s.recv(1024) == b"":
                    closed_after = time.time() - t0
                    break
            except socket.timeout:
                continue
            except OSError:
                closed_after = time.time() - t0
                break
        result["closed_after_s"] = round(closed_after, 1) if closed_after else None
        stop.wait()
    r = measure(SERVER, "slowloris headers", trickle)
    # kHandshakeTimeout (10 s) covers the whole request; a few seconds' slack for the trickle loop.
    assert r["closed_after_s"] is not None and r["closed_after_s"] < 14, r


if __name__ == "__main__":
    with Server() as SERVER:
        run_tests([test_slow_reader_is_bounded, test_1000_connections_are_capped_per_address,
                   test_1_gb_frame_header_is_refused_unread, test_ping_only_client_is_paced,
                   test_10000_tf_edits_per_second_are_paced, test_slowloris_is_cut_by_the_request_timeout])
