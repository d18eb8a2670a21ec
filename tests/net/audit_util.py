"""Shared by the test_audit_*.py files, an outside audit of the running server (what each holds:
its own docstring): raw HTTP requests and WebSocket upgrades over sockets (for bytes urllib would
not send), error-body checks, upload and listing helpers, the server-path checks, and the fixtures
(volumes in NRRD, zarr, gzip and zstd) the tests write into temporary folders. Traffic goes to
127.0.0.1 only; every wait is bounded."""
import contextlib, gzip, json, os, pathlib, socket, time
import urllib.parse

from harness import *  # noqa: F401,F403

TOKEN = "audit-token-5c1e9b"
SANITIZED = os.environ.get("PEAKCAST_SANITIZER", "none") != "none"
FAST = 2.0  # seconds: what "answered at once" means here, with room for a loaded machine
KANA = "データ" * 23 + ".raw"  # 211 bytes in UTF-8: a 200-byte cut splits a character
AUTH = {"Authorization": f"Bearer {TOKEN}"}


# ---------------------------------------------------------------------------------------------
# Helpers

@contextlib.contextmanager
def serve(*args, **kw):
    """A Server that is killed, not asked to stop, when the test fails: a server wedged by one of
    the audit's requests (a FIFO, a loader busy for half a minute) must not hold the run."""
    s = Server(*args, **kw)
    try:
        yield s
    except BaseException:
        if s.alive():
            s.proc.kill()
        try:
            s.stop()
        except Exception:  # noqa: BLE001 - the test's own failure is the one to report
            pass
        raise
    s.stop()


def parse_answer(buf, closed=False):
    """(status, headers, body) once `buf` holds a whole HTTP answer, else None."""
    end = buf.find(b"\r\n\r\n")
    if end < 0:
        return None
    lines = buf[:end].split(b"\r\n")
    status = int(lines[0].split()[1])
    headers = {}
    for line in lines[1:]:
        k, _, v = line.partition(b":")
        headers[k.strip().lower().decode("latin-1")] = v.strip().decode("latin-1")
    rest = buf[end + 4:]
    if status == 100:
        return parse_answer(rest, closed)
    if status == 101:
        return status, headers, b""
    if "content-length" in headers:
        n = int(headers["content-length"])
        return (status, headers, rest[:n]) if len(rest) >= n else None
    return (status, headers, rest) if closed else None


def raw(s, method, target, headers=(), body=b"", host=None, timeout=5.0):
    """One request with exactly these bytes, over its own connection: (status, headers, body).
    host None: the server's own address; False: no Host header at all."""
    if isinstance(target, str):
        target = target.encode()
    out = [method.encode() + b" " + target + b" HTTP/1.1"]
    if host is None:
        host = f"{s.host}:{s.port}"
    if host is not False:
        out.append(b"Host: " + (host if isinstance(host, bytes) else host.encode()))
    for k, v in headers:
        out.append((k if isinstance(k, bytes) else k.encode()) + b": " + (v if isinstance(v, bytes) else v.encode()))
    if body or method in ("POST", "PUT"):
        out.append(b"Content-Length: " + str(len(body)).encode())
    out.append(b"Connection: close")
    data = b"\r\n".join(out) + b"\r\n\r\n" + body
    deadline = time.time() + timeout
    with socket.create_connection((s.host, s.port), timeout=timeout) as c:
        c.sendall(data)
        buf = b""
        while True:
            got = parse_answer(buf)
            if got:
                return got
            left = deadline - time.time()
            if left <= 0:
                raise TimeoutError(f"no whole answer within {timeout} s to {data[:100]!r}")
            c.settimeout(left)
            try:
                chunk = c.recv(65536)
            except ConnectionResetError:
                chunk = b""
            if not chunk:
                got = parse_answer(buf, closed=True)
                if got:
                    return got
                raise ConnectionError(f"the connection closed without an answer to {data[:100]!r}")
            buf += chunk


UPGRADE = [("Upgrade", "websocket"), ("Connection", "Upgrade"), ("Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="),
           ("Sec-WebSocket-Version", "13")]


def ws_upgrade(s, headers=(), host=None, target="/ws"):
    """A WebSocket upgrade by hand: (status, headers, body) of the answer (101: no body)."""
    hs = [h for h in UPGRADE if h[0] != "Connection"] + list(headers)
    if isinstance(target, str):
        target = target.encode()
    out = [b"GET " + target + b" HTTP/1.1"]
    out.append(b"Host: " + (host if isinstance(host, bytes) else (host or f"{s.host}:{s.port}").encode()))
    out.append(b"Connection: Upgrade")
    for k, v in hs:
        out.append((k if isinstance(k, bytes) else k.encode()) + b": " + (v if isinstance(v, bytes) else v.encode()))
    data = b"\r\n".join(out) + b"\r\n\r\n"
    with socket.create_connection((s.host, s.port), timeout=5) as c:
        c.sendall(data)
        buf, deadline = b"", time.time() + 5
        while time.time() < deadline:
            got = parse_answer(buf)
            if got:
                return got
            c.settimeout(max(0.01, deadline - time.time()))
            try:
                chunk = c.recv(65536)
            except (ConnectionResetError, socket.timeout):
                chunk = b""
            if not chunk:
                got = parse_answer(buf, closed=True)
                if got:
                    return got
                raise ConnectionError(f"no answer to the upgrade {data[:200]!r}")
            buf += chunk
        raise TimeoutError("no answer to the upgrade within 5 s")


def error_of(what, status, body, statuses, code=None):
    """The error object of an answer: its status one of `statuses`, its body valid UTF-8 JSON
    with "error" and "message" (and "error" == code when given)."""
    if isinstance(statuses, int):
        statuses = (statuses,)
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError as e:
        raise AssertionError(f"{what}: the error body is not valid UTF-8 ({e}): {body[:200]!r}")
    assert status in statuses, f"{what}: status {status}, expected {statuses}: {text[:300]}"
    try:
        j = json.loads(text)
    except ValueError:
        raise AssertionError(f"{what}: the error body is not JSON: {text[:300]}")
    assert isinstance(j, dict) and isinstance(j.get("error"), str) and isinstance(j.get("message"), str), \
        f"{what}: the error body needs string keys error and message: {text[:300]}"
    if code:
        assert j["error"] == code, f"{what}: error {j['error']!r}, expected {code!r}: {text[:300]}"
    return j


def healthy(s, after):
    """The server lives and answers /api/health with 200 at once."""
    assert s.alive(), f"the server died after {after} (exit {s.proc.poll()}): {''.join(s.log)[-1500:]}"
    try:
        status = http(s, "/api/health", timeout=5)[0]
    except Exception as e:  # noqa: BLE001
        raise AssertionError(f"/api/health did not answer within 5 s after {after}: {e!r}")
    assert status == 200, f"/api/health answered {status} after {after}"


def health(s):
    return json.loads(http(s, "/api/health", timeout=10)[2])


def auth(token):
    return {"Authorization": f"Bearer {token}"} if token else {}


def upload(s, body, query="", token=None, timeout=60):
    h = {"Content-Type": "application/octet-stream", **auth(token)}
    return http(s, "/api/volumes" + ("?" + query if query else ""), "POST", body, h, timeout=timeout)


def delete(s, vid, token=None):
    return http(s, "/api/volumes/" + urllib.parse.quote(vid, safe=""), "DELETE", headers=auth(token), timeout=30)


def listing(s, token=None):
    status, _, body = http(s, "/api/volumes", headers=auth(token), timeout=30)
    try:
        text = body.decode("utf-8")
    except UnicodeDecodeError as e:
        raise AssertionError(f"GET /api/volumes is not valid UTF-8 ({e}): {body[:300]!r}")
    assert status == 200, f"GET /api/volumes: {status} {text[:300]}"
    return json.loads(text)


def render(s, volume, token=None, size=16, extra=None):
    scene = {"volume": volume, "image": {"width": size, "height": size}, **(extra or {})}
    return http(s, "/api/render", "POST", json.dumps(scene).encode(), auth(token), timeout=60)


def server_paths(*dirs):
    """The server-side paths no answer may show: the test's folders and tests/data."""
    out = set()
    for d in (*dirs, DATA):
        out |= {str(d), os.path.realpath(d)}
    return sorted(out, key=len, reverse=True)


def assert_no_paths(texts, paths):
    for what, text in texts:
        if isinstance(text, bytes):
            text = text.decode("utf-8", "replace")
        for p in paths:
            assert p not in text, f"{what}: the answer shows the server path {p}: {text[:400]}"


def ws_texts(client, label="WS"):
    """A client's text messages as (what, text) for assert_no_paths. A `loading` message's volume is
    the client's own name for it (proto/server_messages: "as the client named it"): an echo of the
    request, left out of the check."""
    out = []
    for m in client.texts:
        if m.get("type") == "loading":
            m = {k: v for k, v in m.items() if k != "volume"}
        out.append((f"{label} {m.get('type')}", json.dumps(m, ensure_ascii=False)))
    return out


def leftovers(updir, kept_ids=()):
    """Files in the upload folder that belong to no kept upload (and anything in .incoming)."""
    out = []
    for p in pathlib.Path(updir).iterdir():
        if p.name == ".incoming":
            out += [f".incoming/{q.name}" for q in p.iterdir()]
        elif not any(p.name.startswith(i + ".") for i in kept_ids):
            out.append(p.name)
    return sorted(out)


def vm_kib(s, key):
    for line in open(f"/proc/{s.proc.pid}/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1])
    return 0


# Fixtures ------------------------------------------------------------------------------------

def voxels(n):
    return bytes((i * 37 + 11) % 251 for i in range(n))


def nrrd(sizes=(8, 8, 8), type_=b"uint8", data=None, encoding=b"raw", extra=b""):
    n = sizes[0] * sizes[1] * sizes[2]
    head = (b"NRRD0004\ntype: " + type_ + b"\ndimension: 3\nsizes: " + b" ".join(str(x).encode() for x in sizes) +
            b"\nencoding: " + encoding + b"\n" + extra + b"\n")
    return head + (voxels(n) if data is None else data)


def nhdr(data_file, sizes=(8, 8, 8)):
    return (b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: " + b" ".join(str(x).encode() for x in sizes) +
            b"\nencoding: raw\ndata file: " + data_file.encode() + b"\n")


def zarray(shape, chunks, compressor=None):
    return json.dumps({"zarr_format": 2, "shape": shape, "chunks": chunks, "dtype": "|u1", "compressor": compressor,
                       "fill_value": 0, "order": "C", "filters": None})


ZATTRS = json.dumps({"multiscales": [{"version": "0.4", "axes": [{"name": a, "type": "space"} for a in "zyx"],
                                      "datasets": [{"path": "0", "coordinateTransformations": [
                                          {"type": "scale", "scale": [1, 1, 1]}]}]}]})


def zstd_zeros(n):
    """A zstd frame that decodes to n zero bytes (n a multiple of 1 MiB): python3-zstandard, else
    numcodecs (python3-zarr), else a frame of RLE blocks written by hand (RFC 8878: 128 KiB window,
    each block 3 header bytes and the byte to repeat)."""
    try:
        import zstandard
        c = zstandard.ZstdCompressor(level=1).compressobj()
        block = bytes(1 << 20)
        return b"".join([c.compress(block) for _ in range(n >> 20)] + [c.flush()])
    except ImportError:
        pass
    try:
        import numcodecs, numpy
        return bytes(numcodecs.Zstd(level=1).encode(numpy.zeros(n, numpy.uint8)))
    except ImportError:
        pass
    blk = 1 << 17
    k = n // blk
    out = bytearray(b"\x28\xb5\x2f\xfd\x00\x38")
    for i in range(k):
        out += ((blk << 3) | (1 << 1) | (i == k - 1)).to_bytes(3, "little") + b"\x00"
    return bytes(out)


_GZ = {}


def gzip_zeros_nrrd():
    """An NRRD of 400^3 uint8 zeros, gzip-encoded: about 62 KB that inflate to 64,000,000 bytes."""
    if "nrrd" not in _GZ:
        _GZ["nrrd"] = (b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 400 400 400\nencoding: gzip\n\n" +
                       gzip.compress(bytes(400 ** 3), 9))
    return _GZ["nrrd"]


def unblock_fifo(path, seconds=0.5):
    """Opens the FIFO for writing and closes it, again and again for a while: whoever is stuck in
    open() for reading gets its end-of-file (a cleanup for a server that opened it)."""
    end = time.time() + seconds
    while time.time() < end:
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:
            pass
        time.sleep(0.02)
