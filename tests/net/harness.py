"""Shared by the net tests: start a real `peakcast serve` on a free loopback port, talk to it over
HTTP and WebSocket (Debian's python3-websockets), validate every server message against proto/,
decode frames. Each test file runs its functions and ends with 'N passed, N failed'."""
import asyncio, io, json, math, os, pathlib, re, signal, struct, subprocess, sys, tempfile, threading, time, traceback
import urllib.request, urllib.error

import jsonschema
import websockets
from PIL import Image

ROOT = pathlib.Path(__file__).resolve().parents[2]
PEAKCAST = os.environ.get("PEAKCAST_BIN", str(ROOT / "build/server/peakcast"))
DATA = ROOT / "tests/data"


def _schema_validator(name):
    store = {}
    for f in ("scene", "client_messages", "server_messages"):
        s = json.loads((ROOT / "proto" / f"{f}.schema.json").read_text())
        store[s["$id"]] = s
    target = store[f"urn:peakcast:{name}"]
    resolver = jsonschema.RefResolver.from_schema(target, store=store)
    return jsonschema.Draft202012Validator(target, resolver=resolver)


SERVER_SCHEMA = _schema_validator("server")
CLIENT_SCHEMA = _schema_validator("client")
seen_messages = {"count": 0}


def check_server_message(text):
    """Every text message the server sends must validate against proto/server_messages."""
    msg = json.loads(text)
    errors = sorted(SERVER_SCHEMA.iter_errors(msg), key=str)
    assert not errors, f"server message violates proto: {errors[0].message}: {text[:300]}"
    seen_messages["count"] += 1
    return msg


class Server:
    def __init__(self, *args, volumes=("heptane_151.nrrd",), launcher=(), env=None):
        # launcher: a command the server runs under (mpirun -np N for the mpi label's tests).
        cmd = [*launcher, PEAKCAST, "serve", "--port", "0", "--data", str(DATA)]
        for v in volumes:
            cmd += ["--volume", str(DATA / v)]
        cmd += list(args)
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
        self.log = []
        deadline = time.time() + 60
        while time.time() < deadline:
            line = self.proc.stdout.readline()
            if not line:
                break
            self.log.append(line)
            m = re.search(r"serving on http://([\d.]+):(\d+)", line)
            if m:
                self.host, self.port = m.group(1), int(m.group(2))
                # Keep reading the server's output, so a long test never fills the pipe (the
                # server would block writing its log).
                self.reader = threading.Thread(target=self._drain, daemon=True)
                self.reader.start()
                return
        self.proc.kill()
        raise RuntimeError("server did not start: " + "".join(self.log))

    @property
    def base(self):
        return f"http://{self.host}:{self.port}"

    @property
    def ws_url(self):
        return f"ws://{self.host}:{self.port}/ws"

    def rss_kib(self):
        for line in open(f"/proc/{self.proc.pid}/status"):
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        return 0

    def _drain(self):
        for line in self.proc.stdout:
            self.log.append(line)

    def alive(self):
        return self.proc.poll() is None

    def stop(self):
        if self.alive():
            self.proc.send_signal(signal.SIGTERM)
            try:
                # Past the sanitizer builds' shutdown grace (30 s): a report being written finishes.
                self.proc.wait(40)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        # A sanitizer build reports on the server's stderr: a report fails the test that ran it.
        self.reader.join(10)
        rest = "".join(self.log)
        markers = ("WARNING: ThreadSanitizer", "ERROR: AddressSanitizer", "runtime error:", "ERROR: LeakSanitizer")
        if any(m in rest for m in markers):
            print(rest[-30000:])
            raise AssertionError("the server's sanitizer reported an error (above)")
        return self.proc.returncode

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.stop()


def http(server, path, method="GET", body=None, headers=None, timeout=180):
    """One request; the answer's (status, headers, body). The timeout only ends a hung test: a
    sanitizer build on a loaded 2-core machine takes tens of seconds over a peaks still."""
    req = urllib.request.Request(server.base + path, data=body, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(req, timeout=timeout) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), e.read()


def parse_frame(data):
    magic, version, size, frame_id, flags, cv, tv, rv, w, h, q = struct.unpack_from("<IHHIIIIIIII", data, 0)
    t_in, t_render, t_encode = struct.unpack_from("<QQQ", data, 40)
    assert magic == 0x31464350 and version == 1 and size == 64, "bad frame header"
    return {"id": frame_id, "flags": flags, "final": bool(flags & 1), "interactive": bool(flags & 2),
            "png": bool(flags & 4), "camera_version": cv, "tf_version": tv, "render_version": rv, "width": w,
            "height": h, "quality": q, "t_input_us": t_in, "t_render_us": t_render, "t_encode_us": t_encode,
            "image": data[64:]}


def decode_image(data):
    img = Image.open(io.BytesIO(data)).convert("RGB")
    return img


def psnr(a, b):
    a, b = a.convert("RGB"), b.convert("RGB")
    assert a.size == b.size, f"sizes differ {a.size} {b.size}"
    pa, pb = a.tobytes(), b.tobytes()
    se = sum((x - y) ** 2 for x, y in zip(pa, pb))
    if se == 0:
        return 200.0
    rmse = math.sqrt(se / len(pa)) / 255.0
    return 20 * math.log10(1.0 / rmse)


class Client:
    """A WebSocket viewer: hello, collects messages, acks frames unless told not to."""

    def __init__(self, ws, ack=True):
        self.ws, self.ack, self.texts, self.frames = ws, ack, [], []
        self.unread_frames = []  # frames stats_of received while it looked: next_frame's first

    @classmethod
    async def connect(cls, server, ack=True, **kw):
        ws = await websockets.connect(server.ws_url, max_size=None, open_timeout=30, **kw)
        return cls(ws, ack)

    async def send(self, obj):
        await self.ws.send(obj if isinstance(obj, str) else json.dumps(obj))

    async def hello(self, width=160, height=120, **extra):
        await self.send({"type": "hello", "viewport": {"width": width, "height": height}, **extra})
        return await self.next_text("welcome")

    async def recv(self, timeout=30):
        m = await asyncio.wait_for(self.ws.recv(), timeout)
        if isinstance(m, bytes):
            f = parse_frame(m)
            self.frames.append(f)
            if self.ack:
                await self.send({"type": "ack", "frame": f["id"]})
            return f
        msg = check_server_message(m)
        self.texts.append(msg)
        return msg

    async def next_text(self, type_, timeout=30):
        deadline = time.time() + timeout
        while time.time() < deadline:
            m = await self.recv(deadline - time.time())
            if isinstance(m, dict) and m.get("type") == type_ and "image" not in m:
                return m
        raise TimeoutError(f"no {type_} message")

    async def stats_of(self, frame, timeout=30):
        """The stats message of frame `frame["id"]`, received already or still to come. A frame's
        stats need not follow it: the encode threads hand frames on in the order they finish."""
        deadline = time.time() + timeout
        seen = 0
        while True:
            for m in self.texts[seen:]:
                if m.get("type") == "stats" and m.get("frame") == frame["id"]:
                    return m
            seen = len(self.texts)
            if time.time() >= deadline:
                raise TimeoutError(f"no stats for frame {frame['id']}")
            m = await self.recv(deadline - time.time())
            if "image" in m:
                self.unread_frames.append(m)

    async def next_frame(self, final=None, timeout=60):
        while self.unread_frames:
            m = self.unread_frames.pop(0)
            if final is None or m["final"] == final:
                return m
        deadline = time.time() + timeout
        while time.time() < deadline:
            m = await self.recv(deadline - time.time())
            if "image" in m and (final is None or m["final"] == final):
                return m
        raise TimeoutError("no frame")

    async def close(self):
        await self.ws.close()


def run_tests(tests):
    passed = failed = 0
    for t in tests:
        start = time.time()
        try:
            r = t()
            if asyncio.iscoroutine(r):
                asyncio.run(r)
            print(f"ok   {t.__name__} ({time.time() - start:.1f} s)", flush=True)
            passed += 1
        except Exception:
            print(f"FAIL {t.__name__}", flush=True)
            traceback.print_exc()
            failed += 1
    print(f"server messages validated against proto/: {seen_messages['count']}")
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)
