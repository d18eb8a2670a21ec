#!/usr/bin/env python3
"""An outside audit of the running server, held by the real server: one test (or a few) per point of the
contract the fixes follow. Each reproduces what the audit did and checks what the server must do
instead: static files and docs from a fixed list only, JSON errors that are valid UTF-8 whatever
bytes came in, upload names and headers that cannot name another file, no session slot or upload
slot for who has not earned it, chunked readers that refuse before they read or decode, links out
of the data directories refused at every open, no server path in any answer, allowed hosts,
tokens from files, owned uploads. Fixtures are written here, into temporary folders; traffic goes
to 127.0.0.1 only; every wait is bounded. Requests whose bytes urllib would not send go over raw
sockets."""
import asyncio, contextlib, gzip, json, os, pathlib, re, resource, select, socket, stat, sys, tempfile, threading, time
import urllib.parse

sys.path.insert(0, str(pathlib.Path(__file__).parent))
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


# ---------------------------------------------------------------------------------------------
# 1. Static files and docs: a fixed list of regular files under the web dir and docs/.

def test_1_absolute_paths_after_the_slash_are_not_served():
    """`//proc/self/cmdline` (the command line holds --token), `//proc/self/environ`,
    `//etc/passwd`, `/docs//abs/path/README.md`: 404 not_found at once, no byte of the file."""
    with tempfile.TemporaryDirectory() as tmp, serve("--token", TOKEN) as s:
        pathlib.Path(tmp, "README.md").write_text("audit secret 9d1c\n")
        pathlib.Path(tmp, "page.html").write_text("<p>audit secret 9d1c</p>\n")
        for target in ("//proc/self/cmdline", "//proc/self/environ", "//etc/passwd", "//etc/hostname",
                       f"/docs/{tmp}/README.md", f"/{tmp}/page.html", f"/{tmp}/README.md"):
            t0 = time.time()
            status, _, body = raw(s, "GET", target)
            took = time.time() - t0
            assert TOKEN.encode() not in body and b"audit secret" not in body and b"root:" not in body, \
                f"GET {target} answered the file's bytes: {body[:200]!r}"
            error_of(f"GET {target}", status, body, 404, "not_found")
            assert took < FAST, f"GET {target} took {took:.1f} s"
            healthy(s, f"GET {target}")
        assert raw(s, "GET", "/")[0] == 200, "the client's page must still be served"


def test_1_dev_zero_is_not_read():
    """`GET //dev/zero`: 404 at once; the process lives (it read /dev/zero until bad_alloc). The
    server's address space is capped at 3 GiB over what it uses, so a server that reads without
    limit fails at the cap instead of taking the machine's memory (not under a sanitizer, whose
    shadow memory needs the space)."""
    with serve() as s:
        if not SANITIZED:
            cap = vm_kib(s, "VmPeak") * 1024 + (3 << 30)
            resource.prlimit(s.proc.pid, resource.RLIMIT_AS, (cap, cap))
        t0 = time.time()
        status, _, body = raw(s, "GET", "//dev/zero", timeout=10)
        error_of("GET //dev/zero", status, body, 404, "not_found")
        assert time.time() - t0 < FAST, f"GET //dev/zero took {time.time() - t0:.1f} s"
        healthy(s, "GET //dev/zero")


def test_1_a_fifo_blocks_no_thread():
    """Two requests for a FIFO (by absolute path after `//`, and under /docs/): each answers 404 at
    once, and /api/health answers meanwhile (both io threads were stuck in open())."""
    with tempfile.TemporaryDirectory() as tmp:
        fifo, fifo_md = os.path.join(tmp, "pipe"), os.path.join(tmp, "pipe.md")
        os.mkfifo(fifo)
        os.mkfifo(fifo_md)
        try:
            with serve() as s:
                answers, threads = [], []

                def ask(target):
                    try:
                        answers.append((target, raw(s, "GET", target, timeout=4)))
                    except Exception as e:  # noqa: BLE001
                        answers.append((target, e))

                for target in (f"/{fifo}", f"/docs/{fifo_md}", f"/{fifo}"):
                    t = threading.Thread(target=ask, args=(target,), daemon=True)
                    t.start()
                    threads.append(t)
                    time.sleep(0.1)
                t0 = time.time()
                try:
                    status = http(s, "/api/health", timeout=3)[0]
                except Exception as e:  # noqa: BLE001
                    raise AssertionError(f"/api/health did not answer within 3 s while FIFOs were asked for: {e!r}")
                assert status == 200 and time.time() - t0 < FAST, f"/api/health: {status} in {time.time() - t0:.1f} s"
                for t in threads:
                    t.join(6)
                assert len(answers) == 3, f"answers to the 3 FIFO requests: {answers}"
                for target, a in answers:
                    assert not isinstance(a, Exception), f"GET {target} (a FIFO): no answer: {a!r}"
                    error_of(f"GET {target} (a FIFO)", a[0], a[2], 404, "not_found")
                healthy(s, "the FIFO requests")
        finally:
            unblock_fifo(fifo)
            unblock_fifo(fifo_md)


def test_1_web_dir_serves_only_regular_files_inside_listed_at_start():
    """--web-dir with a link to /etc/passwd, a link to a file outside, a FIFO, and docs/ beside
    it with the same: only the regular files inside, listed at start-up, are served; a file
    created after start-up is not."""
    with tempfile.TemporaryDirectory() as tmp:
        web, docs, out = pathlib.Path(tmp, "web"), pathlib.Path(tmp, "docs"), pathlib.Path(tmp, "outside")
        for d in (web, docs, out):
            d.mkdir()
        (web / "index.html").write_text("<!doctype html><title>audit</title>\n")
        (web / "app.js").write_text("console.log('audit');\n")
        (docs / "guide.md").write_text("# guide\n")
        (out / "secret.md").write_text("audit secret 3b7f\n")
        os.symlink("/etc/passwd", web / "passwd.html")
        os.symlink(out / "secret.md", web / "secret.html")
        os.symlink(out / "secret.md", docs / "leak.md")
        os.mkfifo(web / "pipe.html")
        os.mkfifo(docs / "pipe.md")
        try:
            with serve("--web-dir", str(web)) as s:
                for target in ("/", "/index.html", "/app.js", "/docs/guide.md"):
                    status, _, body = raw(s, "GET", target)
                    assert status == 200, f"GET {target}: {status} {body[:200]!r} (a regular file inside must be served)"
                (web / "later.html").write_text("created after start-up\n")
                (docs / "later.md").write_text("created after start-up\n")
                for target in ("/passwd.html", "/secret.html", "/docs/leak.md", "/pipe.html", "/docs/pipe.md",
                               "/later.html", "/docs/later.md", "/docs/../web/index.html", "/docs/%2e%2e/outside/secret.md"):
                    t0 = time.time()
                    try:
                        status, _, body = raw(s, "GET", target, timeout=4)
                    except TimeoutError:
                        raise AssertionError(f"GET {target}: no answer within 4 s")
                    assert b"audit secret" not in body and b"root:" not in body and b"created after" not in body, \
                        f"GET {target} served the file: {body[:200]!r}"
                    error_of(f"GET {target}", status, body, (400, 404))
                    assert time.time() - t0 < FAST, f"GET {target} took {time.time() - t0:.1f} s"
                    healthy(s, f"GET {target}")
        finally:
            unblock_fifo(str(web / "pipe.html"))
            unblock_fifo(str(docs / "pipe.md"))


# ---------------------------------------------------------------------------------------------
# 2. Bytes that are not UTF-8 never reach a JSON dump unrepaired; the process never dies.

def test_2_raw_ff_in_the_request_line():
    with serve("--token", TOKEN) as s:
        status, _, body = raw(s, "GET", b"/\xff")
        error_of("GET /\\xff", status, body, 404)
        healthy(s, "GET /\\xff")
        status, _, body = raw(s, "GET", b"/docs/\xff\xfe.md")
        error_of("GET /docs/\\xff\\xfe.md", status, body, 404)
        healthy(s, "GET /docs/\\xff\\xfe.md")


def test_2_ff_in_the_origin_of_an_upgrade():
    with serve("--token", TOKEN) as s:
        status, _, body = ws_upgrade(s, [("Origin", b"http://\xff"), ("Authorization", f"Bearer {TOKEN}")])
        error_of("WS upgrade with Origin http://\\xff", status, body, 403)
        healthy(s, "a WS upgrade with Origin http://\\xff")


def test_2_a_type_cut_inside_a_character_before_hello():
    """`{"type":"aaa...(63)é"}` before hello: the server's 64-byte cut must not split the é."""
    with serve("--token", TOKEN) as s:
        async def run():
            c = Client(await websockets.connect(s.ws_url, extra_headers=AUTH, max_size=None, open_timeout=10))
            await c.send('{"type":"' + "a" * 63 + 'é"}')
            try:
                await c.next_text("error", timeout=10)
            except (websockets.exceptions.ConnectionClosed, TimeoutError, asyncio.TimeoutError) as x:
                raise AssertionError(f"no error message for the type with a split é: {x!r}")
            await c.close()
        asyncio.run(run())
        healthy(s, "a WS type with a split é")


def test_2_percent_ff_in_a_volume_id():
    with serve("--token", TOKEN) as s:
        status, _, body = raw(s, "GET", "/api/volumes/%ff", [("Authorization", f"Bearer {TOKEN}")])
        error_of("GET /api/volumes/%ff", status, body, 404)
        healthy(s, "GET /api/volumes/%ff")
        status, _, body = raw(s, "GET", "/api/volumes/a%ff%fe%c3", [("Authorization", f"Bearer {TOKEN}")])
        error_of("GET /api/volumes/a%ff%fe%c3", status, body, 404)
        healthy(s, "GET /api/volumes/a%ff%fe%c3")


def test_2_percent_ff_in_a_files_dir():
    with serve("--token", TOKEN) as s:
        for q in ("%ff", "headsq%2f%ff", "%c3"):
            status, _, body = raw(s, "GET", f"/api/files?dir={q}", [("Authorization", f"Bearer {TOKEN}")])
            error_of(f"GET /api/files?dir={q}", status, body, 404)
            healthy(s, f"GET /api/files?dir={q}")


def test_2_ff_as_a_render_body():
    with serve("--token", TOKEN) as s:
        for body_in in (b"\xff", b'{"volume": "\xff\xfe"}', b'{"volume": "heptane_151", "\xff": 1}'):
            status, _, body = raw(s, "POST", "/api/render", [("Authorization", f"Bearer {TOKEN}")], body_in)
            error_of(f"POST /api/render {body_in!r}", status, body, (400, 404))
            healthy(s, f"POST /api/render {body_in!r}")
        status, _, body = raw(s, "POST", "/api/render", [("Authorization", f"Bearer {TOKEN}")], b"\xff")
        error_of("POST /api/render \\xff", status, body, 400)


def test_2_ff_in_an_uploaded_nrrd_type():
    with tempfile.TemporaryDirectory() as up, serve("--token", TOKEN, "--upload-dir", up) as s:
        for t in (b"\xff\xfe", b"uint8\xff", b"\xc3"):
            status, _, body = upload(s, nrrd(type_=t), "name=t.nrrd", TOKEN)
            error_of(f"upload of an NRRD with type {t!r}", status, body, tuple(range(400, 500)))
            healthy(s, f"an upload with type {t!r}")
            assert not [v for v in listing(s, TOKEN)["volumes"] if v.get("uploaded")], "a refused upload is listed"
        assert leftovers(up) == [], f"files left in the upload dir: {leftovers(up)}"


# ---------------------------------------------------------------------------------------------
# 3. Upload names: valid UTF-8, cut at a character boundary; listed, viewed, deleted, and again
#    after a restart. A commit that fails leaves nothing.

RAW64 = voxels(64)  # 4x4x4 uint8


def test_3_upload_names_are_valid_utf8_and_survive_a_restart():
    with tempfile.TemporaryDirectory() as up:
        ids, names = {}, {}
        with serve("--upload-dir", up) as s:
            for label, q in (("ff", "name=%ff"), ("kana", "name=" + urllib.parse.quote(KANA))):
                for k in (0, 1):
                    status, _, body = upload(s, RAW64, f"dims=4,4,4&dtype=uint8&{q}")
                    try:
                        text = body.decode("utf-8")
                    except UnicodeDecodeError as e:
                        raise AssertionError(f"upload ?{q}: the answer is not valid UTF-8 ({e}): {body[:300]!r}")
                    assert status == 201, f"upload ?{q[:40]}: {status} {text[:300]}"
                    info = json.loads(text)
                    ids[(label, k)], names[(label, k)] = info["id"], info["name"]
            for k in (0, 1):
                assert "\ufffd" in names[("ff", k)], f"name=%ff kept as {names[('ff', k)]!r}: U+FFFD expected"
                n = names[("kana", k)]
                assert 0 < len(n.encode("utf-8")) <= 200 and n.startswith("データ"), \
                    f"the 211-byte name was kept as {len(n.encode())} bytes: {n!r}"
            assert health(s)["uploads"]["used_bytes"] >= 4 * 64, f"uploads not counted: {health(s)['uploads']}"
            listed = {v["id"]: v["name"] for v in listing(s)["volumes"]}
            for key, vid in ids.items():
                assert listed.get(vid) == names[key], f"upload {key} ({vid}) listed as {listed.get(vid)!r}"

            async def view(vid):
                c = await Client.connect(s)
                w = await c.hello(64, 48, volume=vid)
                assert w["volume"]["id"] == vid, w["volume"]
                await c.next_frame()
                await c.close()
            for key in (("ff", 0), ("kana", 0)):
                asyncio.run(view(ids[key]))
            for key in (("ff", 0), ("kana", 0)):
                status, _, body = delete(s, ids[key])
                assert status == 200, f"DELETE of upload {key}: {status} {body[:300]!r}"
            listed = {v["id"] for v in listing(s)["volumes"]}
            assert not {ids[("ff", 0)], ids[("kana", 0)]} & listed, "a deleted upload is still listed"
            healthy(s, "the uploads")
        kept = [ids[("ff", 1)], ids[("kana", 1)]]
        assert leftovers(up, kept) == [], f"files of deleted uploads left: {leftovers(up, kept)}"
        with serve("--upload-dir", up) as s:  # the same upload dir after a restart
            listed = {v["id"]: v["name"] for v in listing(s)["volumes"]}
            for key in (("ff", 1), ("kana", 1)):
                assert listed.get(ids[key]) == names[key], \
                    f"after a restart upload {key} is listed as {listed.get(ids[key])!r}, expected {names[key]!r}"
            asyncio.run(view(ids[("kana", 1)]))
            for key in (("ff", 1), ("kana", 1)):
                status, _, body = delete(s, ids[key])
                assert status == 200, f"after a restart, DELETE of upload {key}: {status} {body[:300]!r}"
            assert health(s)["uploads"]["used_bytes"] == 0, health(s)["uploads"]
            healthy(s, "deleting after a restart")
        assert leftovers(up) == [], f"files left in the upload dir: {leftovers(up)}"


def test_3_a_failed_commit_leaves_no_file_and_no_volume():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        cases = [("name=%ff", nrrd(data=b"short"), (422,)),  # truncated, with a name that is not UTF-8
                 ("name=" + urllib.parse.quote(KANA), nrrd(data=b"short"), (422,)),
                 ("name=%ff%fe", b"neither NRRD nor anything\n" * 4, (415,)),
                 ("name=%ff&dims=4,4,4&dtype=uint8", b"x" * 10, (400, 422))]
        for q, body_in, statuses in cases:
            status, _, body = upload(s, body_in, q)
            error_of(f"upload ?{q[:40]}", status, body, statuses)
            healthy(s, f"a failing upload ?{q[:40]}")
            assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], f"upload ?{q[:40]} is listed"
            assert leftovers(up) == [], f"upload ?{q[:40]} left files: {leftovers(up)}"
        assert health(s)["uploads"]["used_bytes"] == 0, health(s)["uploads"]


# ---------------------------------------------------------------------------------------------
# 4. An upload whose header names another file: 415 unsupported_upload, whatever the spelling.

def mha(lines, data=b""):
    return b"\n".join(lines) + b"\n" + data


MHA_HEAD = [b"ObjectType = Image", b"NDims = 3", b"DimSize = 2 2 2", b"ElementType = MET_UCHAR"]


def test_4_uploads_naming_another_file_are_refused():
    variants = {
        "MHA Comment, blank line, ElementDataFile": mha([b"Comment = x", b""] + MHA_HEAD + [b"ElementDataFile = /etc/passwd"]),
        "MHA ElementDataFile\\t=": mha(MHA_HEAD + [b"ElementDataFile\t= /etc/passwd"]),
        "MHA plain": mha(MHA_HEAD + [b"ElementDataFile = /etc/passwd"]),
        "NRRD 'data file :'": nrrd(sizes=(2, 2, 2), data=b"", extra=b"data file : /etc/passwd\n")[:-1],
        "NRRD ' data file:'": nrrd(sizes=(2, 2, 2), data=b"", extra=b" data file: /etc/passwd\n")[:-1],
        "NRRD 'DATA FILE:' after a comment": nrrd(sizes=(2, 2, 2), data=b"", extra=b"# c\nDATA FILE: /etc/passwd\n")[:-1],
    }
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        for what, body_in in variants.items():
            status, _, body = upload(s, body_in, "name=x")
            error_of(f"upload ({what})", status, body, 415, "unsupported_upload")
            assert b"root:" not in body, f"upload ({what}) answered the file's bytes"
            healthy(s, f"upload ({what})")
            assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], f"upload ({what}) is listed"
        # The message tells nothing of the named path: the same text, showing the path in the same
        # form (whole, its last name, or not at all), whether the file or its folder exists or not.
        seen = []
        for path in ("/etc/passwd", "/etc/zz-audit-none", "/zz-audit-dir/zz-audit-none"):
            body_in = mha([b"Comment = x", b""] + MHA_HEAD + [b"ElementDataFile = " + path.encode()])
            status, _, body = upload(s, body_in, "name=x")
            m = error_of(f"upload naming {path}", status, body, 415, "unsupported_upload")["message"]
            base = path.rsplit("/", 1)[1]
            form = "whole" if path in m else "last name" if base in m else "absent"
            seen.append((path, form, m.replace(path, "PATH").replace(base, "PATH"), m))
        assert len({(form, text) for _, form, text, _ in seen}) == 1, \
            "the refusal differs with the named path's existence:\n  " + "\n  ".join(f"{p}: {m}" for p, _, _, m in seen)
        size = str(os.path.getsize("/etc/passwd"))
        assert size not in seen[0][3], f"the refusal tells the named file's size: {seen[0][3]}"
        assert leftovers(up) == [], f"files left in the upload dir: {leftovers(up)}"


# ---------------------------------------------------------------------------------------------
# 5. WebSocket slots go to who holds the token.

async def _pinger(ws, stop):
    n = 0
    try:
        while not stop.is_set():
            await ws.send(json.dumps({"type": "ping", "id": str(n)}))
            n += 1
            try:
                await asyncio.wait_for(ws.recv(), 0.5)
            except asyncio.TimeoutError:
                pass
    except websockets.exceptions.ConnectionClosed:
        pass


def test_5_unauthenticated_websockets_take_no_session_slot():
    """--max-sessions 2, 4 WebSockets without a token sending pings: a viewer with the token (on
    the upgrade) and one with it in hello both get their welcome."""
    with serve("--token", TOKEN, "--max-sessions", "2") as s:
        async def run():
            stop, held, tasks, refused = asyncio.Event(), [], [], 0
            for _ in range(4):
                try:
                    ws = await websockets.connect(s.ws_url, open_timeout=10)
                except websockets.exceptions.InvalidStatusCode:
                    refused += 1
                    continue
                held.append(ws)
                tasks.append(asyncio.create_task(_pinger(ws, stop)))
            await asyncio.sleep(0.5)
            try:
                try:
                    a = Client(await websockets.connect(s.ws_url, extra_headers=AUTH, open_timeout=10))
                except websockets.exceptions.InvalidStatusCode as e:
                    raise AssertionError(f"a viewer with the token was refused ({e.status_code}) while "
                                         f"{len(held)} unauthenticated WebSockets pinged ({refused} refused)")
                w = await a.hello(64, 48)
                assert w["type"] == "welcome"
                b = await Client.connect(s)
                try:
                    w = await b.hello(64, 48, token=TOKEN)
                except websockets.exceptions.ConnectionClosed as e:
                    raise AssertionError(f"a viewer with the token in hello was closed: {e!r}; {b.texts}")
                await a.close()
                await b.close()
            finally:
                stop.set()
                for t in tasks:
                    t.cancel()
                for ws in held:
                    ws.transport.abort()
            assert refused == 0, f"{refused} of 4 upgrades without a token were refused: they need no slot"
        asyncio.run(run())
        healthy(s, "the unauthenticated WebSockets")


def test_5_a_websocket_without_hello_is_closed_within_10_s():
    """Without a token on a server with one: pings do not keep it; no hello in 10 s closes it."""
    with serve("--token", TOKEN) as s:
        async def run():
            ws = await websockets.connect(s.ws_url, open_timeout=10)
            t0 = time.time()
            n = 0
            try:
                while time.time() - t0 < 13:
                    await ws.send(json.dumps({"type": "ping", "id": str(n)}))
                    n += 1
                    try:
                        await asyncio.wait_for(ws.recv(), 1.0)
                    except asyncio.TimeoutError:
                        pass
            except websockets.exceptions.ConnectionClosed:
                took = time.time() - t0
                assert took < 12.5, f"closed only after {took:.1f} s"
                return
            finally:
                ws.transport.abort()
            raise AssertionError(f"a WebSocket without a token sent {n} pings over 13 s and stayed open")
        asyncio.run(run())
        healthy(s, "the WebSocket without hello")


# ---------------------------------------------------------------------------------------------
# 6. Uploads have a minimum rate and a whole-body deadline.

def _drain_answer(c, buf, took):
    """What a connection the server closed still holds: (took, status, body), or status None."""
    try:
        c.settimeout(0.5)
        while True:
            data = c.recv(65536)
            if not data:
                break
            buf += data
    except OSError:
        pass
    got = parse_answer(buf, closed=True)
    return (took, got[0], got[2]) if got else (took, None, buf)


def _trickle(s, count, seconds, chunk=b"\0", every=1.0, length=1_000_000):
    """`count` uploads announcing `length` bytes, each sending `chunk` every `every` seconds:
    for each, (seconds until the server answered, status, body); status None when the server
    closed the connection without an answer; None when it did neither."""
    head = (f"POST /api/volumes?dims=100,100,100&dtype=uint8 HTTP/1.1\r\nHost: {s.host}:{s.port}\r\n"
            f"Content-Type: application/octet-stream\r\nContent-Length: {length}\r\n\r\n").encode()
    socks = []
    for _ in range(count):
        c = socket.create_connection((s.host, s.port), timeout=5)
        c.sendall(head)
        socks.append(c)
    t0, bufs, done, closed = time.time(), [b""] * count, [None] * count, [False] * count
    next_send = t0
    try:
        while time.time() - t0 < seconds and not all(d is not None or cl for d, cl in zip(done, closed)):
            if time.time() >= next_send:
                for i, c in enumerate(socks):
                    if done[i] is None and not closed[i]:
                        try:
                            c.sendall(chunk)
                        except OSError:  # the server hung up: read what it said first
                            closed[i] = True
                            done[i] = _drain_answer(c, bufs[i], time.time() - t0)
                next_send += every
            live = [c for i, c in enumerate(socks) if done[i] is None and not closed[i]]
            r, _, _ = select.select(live, [], [], max(0.0, min(0.2, next_send - time.time())))
            for c in r:
                i = socks.index(c)
                try:
                    data = c.recv(65536)
                except OSError:
                    data = b""
                bufs[i] += data
                got = parse_answer(bufs[i], closed=not data)
                if got:
                    done[i] = (time.time() - t0, got[0], got[2])
                elif not data:
                    closed[i] = True
                    done[i] = (time.time() - t0, None, bufs[i])
    finally:
        for c in socks:
            c.close()
    return done


def test_6_trickle_uploads_are_ended_as_too_slow():
    """--upload-timeout 2 --max-uploads 2: two uploads of 1,000,000 bytes sending a byte a second
    end with 408 upload_too_slow within ~5 s; an honest upload then gets 201 at once."""
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up, "--upload-timeout", "2", "--max-uploads", "2") as s:
        done = _trickle(s, 2, 7.0)
        for i, d in enumerate(done):
            assert d is not None, f"trickle upload {i}: no answer in 7 s (a byte a second kept it alive)"
            took, status, body = d
            assert status is not None, f"trickle upload {i}: closed after {took:.1f} s without an answer"
            error_of(f"trickle upload {i}", status, body, 408, "upload_too_slow")
            assert took < 5.5, f"trickle upload {i} was ended only after {took:.1f} s"
        status, _, body = upload(s, voxels(1_000_000), "dims=100,100,100&dtype=uint8", timeout=30)
        assert status == 201, f"an honest upload after the trickles: {status} {body[:300]!r}"
        healthy(s, "the trickle uploads")
        assert not [p for p in leftovers(up, [json.loads(body)["id"]])], leftovers(up)


def test_6_the_whole_body_has_a_deadline():
    """--upload-deadline 3 with a minimum rate of 1 KiB/s: an upload sending 10 KiB/s (fast enough)
    of 1,000,000 bytes is ended at the deadline with 408 upload_too_slow."""
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up, "--upload-timeout", "1", "--upload-min-rate-kib",
                                                    "1", "--upload-deadline", "3") as s:
        done = _trickle(s, 1, 7.0, chunk=bytes(4096), every=0.4)
        assert done[0] is not None, "an upload over its deadline: no answer in 7 s"
        took, status, body = done[0]
        assert status is not None, f"an upload over its deadline: closed after {took:.1f} s without the 408"
        error_of("an upload past --upload-deadline", status, body, 408, "upload_too_slow")
        assert 2.5 < took < 5.0, f"ended after {took:.1f} s (deadline 3 s)"
        status, _, body = upload(s, voxels(64), "dims=4,4,4&dtype=uint8")
        assert status == 201, f"an honest upload after: {status} {body[:300]!r}"
        healthy(s, "the upload past its deadline")


# ---------------------------------------------------------------------------------------------
# 7. Chunked readers refuse before they probe or decode too much.

PRECOMPUTED = json.dumps({"type": "image", "data_type": "uint8", "num_channels": 1, "scales": [
    {"key": "s0", "size": [4096, 4096, 1], "resolution": [1, 1, 1], "voxel_offset": [0, 0, 0],
     "chunk_sizes": [[1, 1, 1]], "encoding": "raw"}]})


def test_7_precomputed_with_millions_of_chunks_is_refused_at_once():
    """A Neuroglancer `info` of 4096x4096x1 in 1x1x1 chunks (16.7 M missing chunks): refused in
    under 2 s; /api/files answers within 1 s while it and another volume load."""
    with tempfile.TemporaryDirectory() as tmp:
        pathlib.Path(tmp, "pre").mkdir()
        pathlib.Path(tmp, "pre", "info").write_text(PRECOMPUTED)
        pathlib.Path(tmp, "pre", "s0").mkdir()
        pathlib.Path(tmp, "zeros.nrrd").write_bytes(gzip_zeros_nrrd())
        with serve("--data", tmp, volumes=()) as s:
            answers = {}

            def load(vol):
                t0 = time.time()
                try:
                    st, _, b = render(s, vol)
                    answers[vol] = (time.time() - t0, st, b)
                except Exception as e:  # noqa: BLE001
                    answers[vol] = (time.time() - t0, None, repr(e).encode())
            # "pre" first: the loader is one thread, and the refusal is timed, not the wait behind
            # the 64 MB gzip volume (seconds under a sanitizer).
            threads = [threading.Thread(target=load, args=(v,), daemon=True) for v in ("pre", "zeros.nrrd")]
            for t in threads:
                t.start()
                time.sleep(0.05)
            t0 = time.time()
            try:
                status, _, body = raw(s, "GET", "/api/files", timeout=5)
            except TimeoutError:
                raise AssertionError("/api/files: no answer within 5 s while volumes load")
            took = time.time() - t0
            assert status == 200, f"/api/files: {status} {body[:200]!r}"
            assert took < 1.0, f"/api/files took {took:.1f} s while volumes loaded"
            slow = 4 if SANITIZED else 1  # a sanitizer's server starts, parses and answers more slowly
            threads[0].join(4 * slow)
            assert "pre" in answers, f"the precomputed volume: no answer within {4 * slow} s"
            took, status, body = answers["pre"]
            assert status is not None, f"the precomputed volume: {body!r}"
            error_of("the precomputed volume of 16.7 M chunks", status, body, tuple(range(400, 500)))
            assert took < 2.0 * slow, f"the precomputed volume was refused only after {took:.1f} s"
            threads[1].join(30)
            healthy(s, "the precomputed volume")


def test_7_zarr_chunks_that_decode_past_the_budget_are_refused_before_decoding():
    """A zarr array of 8x64x64 in chunks of 2x16384x16384 (zstd, 16 KB each, 512 MiB decoded)
    under --memory-budget-mib 64: refused, and the server's RSS stays below 300 MB."""
    with tempfile.TemporaryDirectory() as tmp:
        z = pathlib.Path(tmp, "big.zarr")
        z.mkdir()
        (z / ".zarray").write_text(zarray([8, 64, 64], [2, 16384, 16384], {"id": "zstd", "level": 1}))
        chunk = zstd_zeros(2 * 16384 * 16384)
        assert len(chunk) < 1 << 20, len(chunk)
        for k in range(4):
            (z / f"{k}.0.0").write_bytes(chunk)
        with serve("--data", tmp, "--memory-budget-mib", "64", volumes=()) as s:
            before = vm_kib(s, "VmHWM")
            status, _, body = render(s, "big.zarr")
            peak = vm_kib(s, "VmHWM")
            print(f"  peak RSS {before // 1024} MiB before, {peak // 1024} MiB after the request")
            error_of("a zarr whose chunks decode to 512 MiB", status, body, tuple(range(400, 500)))
            if not SANITIZED:
                assert peak < 300 * 1024, f"the server's peak RSS reached {peak // 1024} MiB"
            healthy(s, "the zarr of 512 MiB chunks")


# ---------------------------------------------------------------------------------------------
# 8. An upload counts what it decodes to.

def test_8_a_gzip_upload_counts_its_decoded_bytes():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        status, _, body = upload(s, gzip_zeros_nrrd(), "name=zeros.nrrd")
        assert status == 201, f"the gzip NRRD of 400^3 zeros: {status} {body[:300]!r}"
        used = health(s)["uploads"]["used_bytes"]
        assert 64_000_000 <= used < 64_000_000 + (1 << 20), \
            f"uploads.used_bytes is {used} for a volume of 64,000,000 bytes ({len(gzip_zeros_nrrd())} sent)"
        healthy(s, "the gzip upload")


def test_8_a_gzip_upload_over_the_budget_is_refused_before_decoding():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up, "--upload-budget-mib", "32") as s:
        before = vm_kib(s, "VmHWM")
        status, _, body = upload(s, gzip_zeros_nrrd(), "name=zeros.nrrd")
        peak = vm_kib(s, "VmHWM")
        error_of("the gzip NRRD of 64,000,000 bytes under a 32 MiB budget", status, body, 507, "upload_budget")
        if not SANITIZED:
            assert peak - before < 48 * 1024, f"the peak RSS grew by {(peak - before) // 1024} MiB: decoded first"
        assert health(s)["uploads"]["used_bytes"] == 0, health(s)["uploads"]
        assert leftovers(up) == [], leftovers(up)
        healthy(s, "the upload over the budget")


# ---------------------------------------------------------------------------------------------
# 9. Links out of the data directories are refused at every open.

def _links_fixture(tmp):
    data, out = pathlib.Path(tmp, "data"), pathlib.Path(tmp, "outside")
    data.mkdir()
    out.mkdir()
    (out / "secret.bin").write_bytes(bytes([200]) * 512)
    # A zarr array read through a chunk, a metadata file, or a level folder that lie outside.
    for name in ("ok.zarr", "chunk_link.zarr", "meta_link.zarr"):
        (data / name).mkdir()
    (data / "ok.zarr" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    (data / "ok.zarr" / "0.0.0").write_bytes(voxels(512))
    (data / "chunk_link.zarr" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    os.symlink(out / "secret.bin", data / "chunk_link.zarr" / "0.0.0")
    (out / "meta").mkdir()
    (out / "meta" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    os.symlink(out / "meta" / ".zarray", data / "meta_link.zarr" / ".zarray")
    (data / "meta_link.zarr" / "0.0.0").write_bytes(voxels(512))
    (out / "level0").mkdir()
    (out / "level0" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    (out / "level0" / "0.0.0").write_bytes(bytes([200]) * 512)
    for name, level in (("ok_levels.zarr", None), ("level_link.zarr", out / "level0")):
        (data / name).mkdir()
        (data / name / ".zattrs").write_text(ZATTRS)
        if level is None:
            (data / name / "0").mkdir()
            (data / name / "0" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
            (data / name / "0" / "0.0.0").write_bytes(voxels(512))
        else:
            os.symlink(level, data / name / "0")
    # Detached NRRD headers whose data file lies outside: absolute, ../, and a link to outside.
    (data / "ok.raw").write_bytes(voxels(512))
    (data / "ok.nhdr").write_bytes(nhdr("ok.raw"))
    (data / "abs.nhdr").write_bytes(nhdr(str(out / "secret.bin")))
    (data / "rel.nhdr").write_bytes(nhdr("../outside/secret.bin"))
    os.symlink(out / "secret.bin", data / "linked.raw")
    (data / "via_link.nhdr").write_bytes(nhdr("linked.raw"))
    return data, out


def _expect_links_refused(refused, controls):
    with tempfile.TemporaryDirectory() as tmp:
        data, out = _links_fixture(tmp)
        with serve("--data", str(data), volumes=()) as s:
            for vol in controls:
                status, _, body = render(s, vol)
                assert status == 200, f"{vol} (all inside the data dir) must open: {status} {body[:300]!r}"
            for vol in refused:
                status, _, body = render(s, vol)
                error_of(f"{vol} (reads a file outside the data dirs)", status, body, tuple(range(400, 500)))
                assert_no_paths([(vol, body)], server_paths(tmp))
                listed = {v["id"] for v in listing(s)["volumes"]}
                assert vol not in listed, f"{vol} was opened and is listed"
                healthy(s, vol)


def test_9_a_zarr_chunk_or_metadata_linked_outside_is_refused():
    _expect_links_refused(["chunk_link.zarr", "meta_link.zarr"], ["ok.zarr"])


def test_9_a_zarr_level_folder_linked_outside_is_refused():
    _expect_links_refused(["level_link.zarr"], ["ok_levels.zarr"])


def test_9_an_nhdr_data_file_outside_is_refused():
    _expect_links_refused(["abs.nhdr", "rel.nhdr", "via_link.nhdr"], ["ok.nhdr"])


# ---------------------------------------------------------------------------------------------
# 10. No server path in any answer (REST or WS); a volume id never carries a path.

def test_10_errors_name_no_server_path():
    """A `.zarray` symlink loop, a ray texture naming an `.nhdr`: over REST and WS, no answer
    shows the data dirs' paths."""
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp)
        (d / "loop.zarr").mkdir()
        os.symlink(".zarray", d / "loop.zarr" / ".zarray")
        (d / "loop2.zarr").mkdir()
        os.symlink("b", d / "loop2.zarr" / ".zarray")
        os.symlink(".zarray", d / "loop2.zarr" / "b")
        (d / "loop3.zarr" / "0").mkdir(parents=True)
        (d / "loop3.zarr" / ".zattrs").write_text(ZATTRS)
        os.symlink(".zarray", d / "loop3.zarr" / "0" / ".zarray")
        (d / "sub").mkdir()
        (d / "sub" / "y.raw").write_bytes(voxels(512))
        (d / "sub" / "y.nhdr").write_bytes(nhdr("y.raw"))
        texts = []
        with serve("--data", tmp) as s:
            for vol in ("loop.zarr", "loop2.zarr", "loop3.zarr", "loop.zarr/.zarray"):
                status, _, body = render(s, vol)
                texts.append((f"render {vol}", body))
                error_of(f"render {vol}", status, body, tuple(range(400, 600)))
                healthy(s, f"render {vol}")
            for png in ("nucleon.nhdr", "sub/y.nhdr", "sub"):
                extra = {"render": {"ray_texture": {"mapping": "view", "png": png}}}
                status, _, body = render(s, "heptane_151", extra=extra)
                texts.append((f"render with ray_texture.png {png}", body))
                error_of(f"render with ray_texture.png {png}", status, body, tuple(range(400, 600)))
                scene = {"volume": "heptane_151", "image": {"width": 16, "height": 16}, "pixel": [8, 8], **extra}
                status, _, body = http(s, "/api/probe", "POST", json.dumps(scene).encode(), timeout=30)
                texts.append((f"probe with ray_texture.png {png}", body))
                error_of(f"probe with ray_texture.png {png}", status, body, tuple(range(400, 600)))

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48)
                for vol in ("loop.zarr", "loop3.zarr"):
                    await c.send({"type": "volume", "volume": vol})
                    e = await c.next_text("error", timeout=30)
                    texts.append((f"WS volume {vol}", json.dumps(e)))
                for png in ("nucleon.nhdr", "sub/y.nhdr"):
                    await c.send({"type": "render", "render": {"ray_texture": {"mapping": "view", "png": png}}})
                    e = await c.next_text("error", timeout=30)
                    texts.append((f"WS ray_texture.png {png}", json.dumps(e, ensure_ascii=False)))
                await c.close()
                texts.extend(ws_texts(c))
            asyncio.run(ws())
            healthy(s, "the errors")
        assert_no_paths(texts, server_paths(tmp))


def test_10_a_damaged_upload_after_a_restart_names_no_path():
    with tempfile.TemporaryDirectory() as up:
        with serve("--upload-dir", up) as s:
            status, _, body = upload(s, nrrd(), "name=scan.nrrd")
            assert status == 201, f"upload: {status} {body[:300]!r}"
            vid = json.loads(body)["id"]
        data = [p for p in pathlib.Path(up).iterdir() if p.name.startswith(vid + ".") and not p.name.endswith(".json")]
        assert len(data) == 1, f"the upload's data file: {[p.name for p in pathlib.Path(up).iterdir()]}"
        data[0].write_bytes(data[0].read_bytes()[:100])  # damaged while the server was down
        texts = []
        with serve("--upload-dir", up) as s:
            texts.append(("GET /api/volumes", http(s, "/api/volumes")[2]))
            status, _, body = http(s, f"/api/volumes/{vid}", timeout=30)
            texts.append((f"GET /api/volumes/{vid}", body))
            error_of(f"GET /api/volumes/{vid} (damaged)", status, body, tuple(range(400, 600)))
            status, _, body = render(s, vid)
            texts.append((f"render {vid}", body))
            error_of(f"render {vid} (damaged)", status, body, tuple(range(400, 600)))

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48)
                await c.send({"type": "volume", "volume": vid})
                e = await c.next_text("error", timeout=30)
                texts.append(("WS volume (damaged upload)", json.dumps(e, ensure_ascii=False)))
                await c.close()
                c2 = await Client.connect(s)
                await c2.send({"type": "hello", "viewport": {"width": 64, "height": 48}, "volume": vid})
                e = await c2.next_text("error", timeout=30)
                texts.append(("WS hello (damaged upload)", json.dumps(e, ensure_ascii=False)))
                await c2.close()
                texts.extend(ws_texts(c) + ws_texts(c2))
            asyncio.run(ws())
            healthy(s, "the damaged upload")
        assert_no_paths(texts, server_paths(up))


def test_10_a_volume_opened_by_absolute_path_gets_a_relative_id():
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp)
        (d / "sub").mkdir()
        (d / "sub" / "x.nrrd").write_bytes(nrrd())
        (d / "x.nrrd").write_bytes(nrrd(sizes=(8, 8, 4), data=voxels(256)))
        texts = []
        with serve("--data", tmp) as s:
            status, headers, body = render(s, f"{tmp}/sub/x.nrrd")
            assert status == 200, f"render by absolute path inside a data dir: {status} {body[:300]!r}"
            texts.append(("render headers", json.dumps(headers)))
            vols = listing(s)
            texts.append(("GET /api/volumes", json.dumps(vols, ensure_ascii=False)))
            ids = [v["id"] for v in vols["volumes"]]
            assert "sub/x.nrrd" in ids and not [i for i in ids if i.startswith("/")], \
                f"the volume opened by absolute path is listed as {ids}"

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48)
                await c.send({"type": "volume", "volume": f"{tmp}/x.nrrd"})
                m = await c.next_text("volume", timeout=30)
                assert m["volume"]["id"] == "x.nrrd", f"WS volume by absolute path got the id {m['volume']['id']!r}"
                await c.close()
                texts.extend(ws_texts(c))
                c2 = await Client.connect(s)
                w = await c2.hello(64, 48)
                assert not [v["id"] for v in w["volumes"] if v["id"].startswith("/")], w["volumes"]
                texts.append(("WS welcome", json.dumps(w, ensure_ascii=False)))
                await c2.close()
            asyncio.run(ws())
            texts.append(("GET /api/volumes (after WS)", http(s, "/api/volumes")[2]))
            healthy(s, "the volumes opened by absolute path")
        assert_no_paths(texts, server_paths(tmp))


# ---------------------------------------------------------------------------------------------
# 11. A file name that is not UTF-8 in a listed folder.

def test_11_a_file_name_that_is_not_utf8_is_listed_without_error():
    with tempfile.TemporaryDirectory() as tmp:
        sub = pathlib.Path(tmp, "sub")
        sub.mkdir()
        (sub / "ok.raw").write_bytes(voxels(512))
        (sub / "ok.nhdr").write_bytes(nhdr("ok.raw"))
        with open(os.path.join(os.fsencode(str(sub)), b"bad\xff.nhdr"), "wb") as f:
            f.write(nhdr("ok.raw"))
        os.mkdir(os.path.join(os.fsencode(tmp), b"dir\xfe"))
        with serve("--data", tmp, volumes=()) as s:
            for q in ("sub", ""):
                status, _, body = http(s, f"/api/files?dir={q}", timeout=30)
                try:
                    text = body.decode("utf-8")
                except UnicodeDecodeError as e:
                    raise AssertionError(f"/api/files?dir={q} is not valid UTF-8 ({e})")
                assert status == 200, f"/api/files?dir={q}: {status} {text[:300]}"
                names = [e["name"] for e in json.loads(text)["entries"]]
                assert ("ok.nhdr" if q else "sub") in names, f"/api/files?dir={q}: {names}"
            healthy(s, "the listing")


# ---------------------------------------------------------------------------------------------
# 12. A raw upload's size must be its dims' size; every axis at least 2 voxels.

def test_12_a_raw_upload_with_extra_bytes_is_refused():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        status, _, body = upload(s, voxels(1000), "dims=5,10,10&dtype=uint8")
        j = error_of("raw dims=5,10,10 uint8 with 1000 bytes", status, body, 400, "bad_upload")
        assert "500" in j["message"] and "1000" in j["message"], f"the message must name 500 and 1000: {j['message']}"
        assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], "the refused upload is listed"
        status, _, body = upload(s, voxels(1000), "dims=10,10,10&dtype=uint8")
        assert status == 201, f"raw dims=10,10,10 with 1000 bytes: {status} {body[:300]!r}"
        assert leftovers(up, [json.loads(body)["id"]]) == [], leftovers(up)
        healthy(s, "the upload with extra bytes")


def test_12_a_raw_upload_needs_two_voxels_per_axis():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        for dims in ("1000,1,1", "1,1000,1", "10,100,1"):
            status, _, body = upload(s, voxels(1000), f"dims={dims}&dtype=uint8")
            error_of(f"raw dims={dims} uint8", status, body, 400, "bad_upload")
        assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], "a refused upload is listed"
        assert leftovers(up) == [], leftovers(up)
        healthy(s, "the flat uploads")


# ---------------------------------------------------------------------------------------------
# 13. Deleting a viewed upload: the viewer hears it and moves on; the memory goes.

def test_13_a_deleted_upload_moves_its_viewer_and_frees_its_memory():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        h0 = health(s)
        assert "volume_bytes" in h0, f"/api/health has no volume_bytes: {sorted(h0)}"
        b0 = h0["volume_bytes"]
        default = listing(s)["default"]
        status, _, body = upload(s, voxels(64 ** 3), "dims=64,64,64&dtype=uint8&name=viewed")
        assert status == 201, f"upload: {status} {body[:300]!r}"
        vid = json.loads(body)["id"]

        async def run():
            c = await Client.connect(s)
            w = await c.hello(64, 48, volume=vid)
            assert w["volume"]["id"] == vid, w["volume"]
            await c.next_frame()
            b1 = health(s)["volume_bytes"]
            assert b1 >= b0 + 64 ** 3, f"volume_bytes {b1} while the upload is viewed (before: {b0})"
            status, _, body = delete(s, vid)
            assert status == 200, f"DELETE: {status} {body[:300]!r}"
            try:
                e = await c.next_text("error", timeout=10)
            except (TimeoutError, asyncio.TimeoutError):
                raise AssertionError(f"the viewer heard nothing of the deletion: {[m.get('type') for m in c.texts]}")
            assert e["code"] == "volume_deleted", e
            m = await c.next_text("volume", timeout=10)
            assert m["volume"]["id"] == default, f"the viewer was moved to {m['volume']['id']}, not {default}"
            await c.next_frame()
            await c.close()
        asyncio.run(run())
        deadline, b2 = time.time() + 5, None
        while time.time() < deadline:
            b2 = health(s)["volume_bytes"]
            if b2 <= b0:
                break
            time.sleep(0.1)
        assert b2 <= b0, f"volume_bytes {b2} after the delete; {b0} before the upload"
        healthy(s, "the deletion")


# ---------------------------------------------------------------------------------------------
# 14. Tokens compare in constant time.

TOKEN_COMPARISON = re.compile(r"[\w.\->]*token\w*(\(\))?\s*[!=]=[^=]|[!=]=\s*[\w.\->]*token\w*\b(?!\()")


def test_14_tokens_compare_in_constant_time():
    """A source check (timing cannot be measured reliably here): no token is compared with == or
    != in server/; tokens_equal is defined and used. Then wrong tokens of every shape are 401."""
    sources = [p for p in (ROOT / "server").rglob("*") if p.suffix in (".cpp", ".h")]
    direct = [f"{p.relative_to(ROOT)}:{i}: {line.strip()}" for p in sources
              for i, line in enumerate(p.read_text(errors="replace").splitlines(), 1) if TOKEN_COMPARISON.search(line)]
    assert not direct, "tokens compared with == or != (not constant-time):\n  " + "\n  ".join(direct)
    defined = [p for p in sources if re.search(r"\bbool\s+tokens_equal\s*\(", p.read_text(errors="replace"))]
    used = [p for p in sources if re.search(r"[^\w]tokens_equal\s*\(", p.read_text(errors="replace"))]
    assert defined, "tokens_equal is not defined in server/"
    assert len(used) > 1, f"tokens_equal is used only in {[str(p) for p in used]}"
    with serve("--token", TOKEN) as s:
        for wrong in ("", TOKEN[:-1], TOKEN + "x", TOKEN[:-1] + "X", "x" * len(TOKEN), TOKEN.upper()):
            status, _, body = http(s, "/api/volumes", headers={"Authorization": f"Bearer {wrong}"})
            error_of(f"a wrong token {wrong!r}", status, body, 401, "unauthorized")
        assert http(s, "/api/volumes", headers=AUTH)[0] == 200, "the right token is refused"
        healthy(s, "the wrong tokens")


# ---------------------------------------------------------------------------------------------
# Options: allowed hosts (DNS rebinding), tokens from files, owned uploads.

EVIL_HOSTS = ["evil.example:{port}", "evil.example", "127.0.0.1.evil.example:{port}", "localhost.evil.example",
              b"\xff", "evil.example:{port}@127.0.0.1"]


def test_host_a_foreign_host_is_refused_on_every_route():
    """Default config: `Host: evil.example:PORT` (a DNS-rebound page) gets 403 forbidden_host on
    the page, /api/*, /api/health, /metrics, uploads and the WebSocket upgrade (with its Origin),
    while the server's own names and a request without Host are served."""
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        for h in EVIL_HOSTS:
            host = h if isinstance(h, bytes) else h.format(port=s.port)
            for method, target, body in (("GET", "/", b""), ("GET", "/index.html", b""), ("GET", "/api/health", b""),
                                         ("GET", "/api/volumes", b""), ("GET", "/api/files", b""),
                                         ("GET", "/metrics", b""), ("GET", "/docs/rest.md", b""),
                                         ("POST", "/api/volumes?dims=2,2,2&dtype=uint8", voxels(8))):
                status, _, answer = raw(s, method, target, body=body, host=host)
                error_of(f"{method} {target} with Host {host!r}", status, answer, 403, "forbidden_host")
            origin = "http://" + (host.decode("latin-1") if isinstance(host, bytes) else host)
            status, _, answer = ws_upgrade(s, [("Origin", origin.encode("latin-1"))], host=host)
            assert status != 101, f"a WebSocket upgrade with Host {host!r} and Origin {origin!r} was accepted"
            error_of(f"WS upgrade with Host {host!r}", status, answer, 403, "forbidden_host")
        assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], "an upload with a foreign Host was kept"
        for host in (f"127.0.0.1:{s.port}", f"localhost:{s.port}", "LOCALHOST", f"LocalHost:{s.port}",
                     f"[::1]:{s.port}", "127.0.0.1"):
            status, _, body = raw(s, "GET", "/api/health", host=host)
            assert status == 200, f"Host {host!r} is the server's own: {status} {body[:200]!r}"
            status, _, _ = ws_upgrade(s, [("Origin", f"http://{host}")], host=host)
            assert status == 101, f"a WebSocket upgrade with Host {host!r} and its own Origin: {status}"
        status, _, body = raw(s, "GET", "/api/health", host=False)
        assert status == 200, f"a request without Host: {status} {body[:200]!r}"
        healthy(s, "the foreign hosts")


def test_host_allowed_hosts_are_configurable():
    with serve("--allowed-host", "viewer.example", "--allowed-host", "Other.Example") as s:
        for host in ("viewer.example", "viewer.example:8443", "VIEWER.EXAMPLE", "other.example:1", f"localhost:{s.port}"):
            status, _, body = raw(s, "GET", "/api/health", host=host)
            assert status == 200, f"Host {host!r} is allowed: {status} {body[:200]!r}"
        status, _, _ = ws_upgrade(s, [("Origin", f"http://viewer.example:{s.port}")], host=f"viewer.example:{s.port}")
        assert status == 101, f"WS upgrade from the allowed host's own page: {status}"
        status, _, body = ws_upgrade(s, [("Origin", f"http://evil.example:{s.port}")], host=f"viewer.example:{s.port}")
        error_of("WS upgrade from an allowed host with a foreign Origin", status, body, 403, "forbidden_origin")
        status, _, body = raw(s, "GET", "/api/health", host="evil.example")
        error_of("Host evil.example beside --allowed-host", status, body, 403, "forbidden_host")
    with serve("--allowed-host", "*") as s:
        status, _, body = raw(s, "GET", "/api/health", host="anything.example:99")
        assert status == 200, f"--allowed-host '*' allows any Host: {status} {body[:200]!r}"


def test_token_file_holds_the_admin_token():
    with tempfile.TemporaryDirectory() as tmp:
        f = pathlib.Path(tmp, "token")
        f.write_text(f"  {TOKEN}  \nsecond-line-is-not-a-token\n")
        os.chmod(f, stat.S_IRUSR | stat.S_IWUSR)
        with serve("--token-file", str(f)) as s:
            assert TOKEN.encode() not in pathlib.Path(f"/proc/{s.proc.pid}/cmdline").read_bytes()
            assert http(s, "/api/volumes", headers=AUTH)[0] == 200, "the token from the file is not accepted"
            for wrong in (None, "second-line-is-not-a-token", f"  {TOKEN}"):
                status, _, body = http(s, "/api/volumes", headers={"Authorization": f"Bearer {wrong}"} if wrong else {})
                error_of(f"token {wrong!r}", status, body, 401, "unauthorized")

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48, token=TOKEN)
                await c.close()
            asyncio.run(ws())
            healthy(s, "the tokens from a file")


def test_user_tokens_own_their_uploads():
    """--token ADMIN --user-token-file F: users view, render and upload; an upload carries its
    owner; a user deletes only their own (403 not_owner), the admin any."""
    users = {"alice": "tok-alice-71", "bob": "tok-bob-93"}
    with tempfile.TemporaryDirectory() as tmp, tempfile.TemporaryDirectory() as up:
        f = pathlib.Path(tmp, "users")
        f.write_text("# users of the audit\n\nalice tok-alice-71\n  \nbob tok-bob-93\n")
        with serve("--token", TOKEN, "--user-token-file", str(f), "--upload-dir", up) as s:
            ids = {}
            for who, tok in (("alice", users["alice"]), ("bob", users["bob"]), ("admin", TOKEN)):
                status, _, body = upload(s, voxels(512), f"dims=8,8,8&dtype=uint8&name={who}", tok)
                assert status == 201, f"upload by {who}: {status} {body[:300]!r}"
                info = json.loads(body)
                assert info.get("owner") == who, f"upload by {who}: owner {info.get('owner')!r}"
                ids[who] = info["id"]
            owners = {v["id"]: v.get("owner") for v in listing(s, users["bob"])["volumes"] if v.get("uploaded")}
            assert owners == {ids[w]: w for w in ids}, f"GET /api/volumes owners: {owners}"
            status, _, body = render(s, ids["bob"], users["alice"])
            assert status == 200, f"alice renders bob's upload: {status} {body[:200]!r}"
            status, _, body = http(s, "/api/volumes", headers=auth("tok-carol"))
            error_of("an unknown user token", status, body, 401, "unauthorized")
            for who, tok, target in (("bob", users["bob"], "alice"), ("alice", users["alice"], "admin")):
                status, _, body = delete(s, ids[target], tok)
                error_of(f"{who} deletes {target}'s upload", status, body, 403, "not_owner")
            assert {v["id"] for v in listing(s, TOKEN)["volumes"]} >= set(ids.values()), "a refused delete removed it"
            for who, tok, target in (("alice", users["alice"], "alice"), ("admin", TOKEN, "bob"), ("admin", TOKEN, "admin")):
                status, _, body = delete(s, ids[target], tok)
                assert status == 200, f"{who} deletes {target}'s upload: {status} {body[:300]!r}"

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48, token=users["bob"])
                await c.close()
            asyncio.run(ws())
            healthy(s, "the owned uploads")


if __name__ == "__main__":
    run_tests([
        test_1_absolute_paths_after_the_slash_are_not_served, test_1_dev_zero_is_not_read,
        test_1_a_fifo_blocks_no_thread, test_1_web_dir_serves_only_regular_files_inside_listed_at_start,
        test_2_raw_ff_in_the_request_line, test_2_ff_in_the_origin_of_an_upgrade,
        test_2_a_type_cut_inside_a_character_before_hello, test_2_percent_ff_in_a_volume_id,
        test_2_percent_ff_in_a_files_dir, test_2_ff_as_a_render_body, test_2_ff_in_an_uploaded_nrrd_type,
        test_3_upload_names_are_valid_utf8_and_survive_a_restart, test_3_a_failed_commit_leaves_no_file_and_no_volume,
        test_4_uploads_naming_another_file_are_refused,
        test_5_unauthenticated_websockets_take_no_session_slot, test_5_a_websocket_without_hello_is_closed_within_10_s,
        test_6_trickle_uploads_are_ended_as_too_slow, test_6_the_whole_body_has_a_deadline,
        test_7_precomputed_with_millions_of_chunks_is_refused_at_once,
        test_7_zarr_chunks_that_decode_past_the_budget_are_refused_before_decoding,
        test_8_a_gzip_upload_counts_its_decoded_bytes, test_8_a_gzip_upload_over_the_budget_is_refused_before_decoding,
        test_9_a_zarr_chunk_or_metadata_linked_outside_is_refused, test_9_a_zarr_level_folder_linked_outside_is_refused,
        test_9_an_nhdr_data_file_outside_is_refused,
        test_10_errors_name_no_server_path, test_10_a_damaged_upload_after_a_restart_names_no_path,
        test_10_a_volume_opened_by_absolute_path_gets_a_relative_id,
        test_11_a_file_name_that_is_not_utf8_is_listed_without_error,
        test_12_a_raw_upload_with_extra_bytes_is_refused, test_12_a_raw_upload_needs_two_voxels_per_axis,
        test_13_a_deleted_upload_moves_its_viewer_and_frees_its_memory,
        test_14_tokens_compare_in_constant_time,
        test_host_a_foreign_host_is_refused_on_every_route, test_host_allowed_hosts_are_configurable,
        test_token_file_holds_the_admin_token, test_user_tokens_own_their_uploads,
    ])
