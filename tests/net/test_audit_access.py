#!/usr/bin/env python3
"""An outside audit of the running server, held by the real server (one of four test_audit_*.py
files): one test (or a few) per point of the contract the fixes follow. This one: who gets in. No
session slot for who has not earned it, tokens compared in constant time, allowed hosts (DNS
rebinding), tokens from files, and owned uploads. Requests whose bytes urllib would not send go over
raw sockets. Fixtures are written here, into temporary folders; traffic goes to 127.0.0.1 only;
every wait is bounded. The helpers and fixtures are in audit_util.py."""
import asyncio, json, os, pathlib, re, stat, sys, tempfile, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403
from audit_util import *  # noqa: F401,F403


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
        test_5_unauthenticated_websockets_take_no_session_slot, test_5_a_websocket_without_hello_is_closed_within_10_s,
        test_14_tokens_compare_in_constant_time, test_host_a_foreign_host_is_refused_on_every_route,
        test_host_allowed_hosts_are_configurable, test_token_file_holds_the_admin_token,
        test_user_tokens_own_their_uploads,
    ])
