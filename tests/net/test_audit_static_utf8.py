#!/usr/bin/env python3
"""An outside audit of the running server, held by the real server (one of four test_audit_*.py
files): one test (or a few) per point of the contract the fixes follow. This one: static files and
docs from a fixed list only (no absolute path, /dev/zero, FIFO or link is read), and JSON errors
that are valid UTF-8 whatever bytes came in, the process never dying. Requests whose bytes urllib
would not send go over raw sockets. Fixtures are written here, into temporary folders; traffic goes
to 127.0.0.1 only; every wait is bounded. The helpers and fixtures are in audit_util.py."""
import asyncio, os, pathlib, resource, sys, tempfile, threading, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403
from audit_util import *  # noqa: F401,F403


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


if __name__ == "__main__":
    run_tests([
        test_1_absolute_paths_after_the_slash_are_not_served, test_1_dev_zero_is_not_read,
        test_1_a_fifo_blocks_no_thread, test_1_web_dir_serves_only_regular_files_inside_listed_at_start,
        test_2_raw_ff_in_the_request_line, test_2_ff_in_the_origin_of_an_upgrade,
        test_2_a_type_cut_inside_a_character_before_hello, test_2_percent_ff_in_a_volume_id,
        test_2_percent_ff_in_a_files_dir, test_2_ff_as_a_render_body, test_2_ff_in_an_uploaded_nrrd_type,
    ])
