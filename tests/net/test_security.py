#!/usr/bin/env python3
"""Security defaults (docs/architecture.md): token, Origin allow-list, session cap, limits,
data directories, loopback bind, GPU memory budget."""
import asyncio, json, pathlib, sys, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403


async def expect_http_refusal(server, code, path="/ws", headers=None):
    try:
        ws = await websockets.connect(server.ws_url.replace("/ws", path), extra_headers=headers or {}, open_timeout=10)
        await ws.close()
        raise AssertionError("upgrade was accepted")
    except websockets.exceptions.InvalidStatusCode as e:
        assert e.status_code == code, e.status_code
        return e


def test_token():
    with Server("--token", "s3cret") as s:
        async def run():
            # Wrong token on the upgrade: 401 before any WebSocket.
            await expect_http_refusal(s, 401, "/ws?token=wrong")
            # No token on the upgrade, none in hello: error, then the socket closes.
            c = await Client.connect(s)
            await c.send({"type": "hello", "viewport": {"width": 64, "height": 64}})
            e = await c.next_text("error")
            assert e["code"] == "unauthorized"
            try:
                await c.recv(timeout=5)
                raise AssertionError("socket stayed open")
            except websockets.exceptions.ConnectionClosed:
                pass
            # Token in hello (what a browser does), or on the upgrade (scripts).
            c = await Client.connect(s)
            await c.hello(64, 64, token="s3cret")
            await c.next_frame()
            await c.close()
            c = Client(await websockets.connect(s.ws_url, extra_headers={"Authorization": "Bearer s3cret"}))
            await c.hello(64, 64)
            await c.next_frame()
            await c.close()
        asyncio.run(run())
        assert http(s, "/api/volumes")[0] == 401
        assert http(s, "/api/volumes", headers={"Authorization": "Bearer nope"})[0] == 401
        assert http(s, "/api/volumes", headers={"Authorization": "Bearer s3cret"})[0] == 200
        assert http(s, "/api/volumes?token=s3cret")[0] == 200
        assert http(s, "/metrics")[0] == 401
        assert http(s, "/api/health")[0] == 200  # liveness probes need no token
        assert http(s, "/")[0] == 200  # the page itself loads, and asks for the token


def test_foreign_origin_refused():
    with Server("--allow-origin", "http://viewer.example") as s:
        async def run():
            await expect_http_refusal(s, 403, headers={"Origin": "http://evil.example"})
            for origin in (f"http://{s.host}:{s.port}", "http://viewer.example"):
                c = Client(await websockets.connect(s.ws_url, origin=origin))
                await c.hello(64, 64)
                await c.close()
        asyncio.run(run())


def test_session_cap_gives_503_with_a_reason():
    with Server("--max-sessions", "2") as s:
        async def run():
            a, b = await Client.connect(s), await Client.connect(s)
            await a.hello(64, 64)
            await b.hello(64, 64)
            e = await expect_http_refusal(s, 503)
            body = json.loads(e.headers.get("X-Body", "{}") or "{}") if False else None
            await a.close()
            for _ in range(100):  # a slot is free again once the server has seen the close
                try:
                    c = await Client.connect(s)
                    break
                except websockets.exceptions.InvalidStatusCode:
                    await asyncio.sleep(0.1)
            await c.hello(64, 64)
            await c.close()
            await b.close()
        asyncio.run(run())
        # The same refusal over plain HTTP shows the JSON reason.
        import socket
        key = "dGhlIHNhbXBsZSBub25jZQ=="
        up = (f"GET /ws HTTP/1.1\r\nHost: {s.host}:{s.port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n")

        def upgrade(raw):
            raw.sendall(up.encode())
            return raw.recv(4096).decode()

        held = []
        try:
            # The sessions above close asynchronously: take both slots once they are free.
            for _ in range(2):
                for _ in range(100):
                    raw = socket.create_connection((s.host, s.port))
                    if upgrade(raw).startswith("HTTP/1.1 101"):
                        held.append(raw)
                        break
                    raw.close()
                    time.sleep(0.1)
            assert len(held) == 2, "the two session slots never came free"
            with socket.create_connection((s.host, s.port)) as raw3:
                reply = upgrade(raw3)
                assert reply.startswith("HTTP/1.1 503"), reply
                assert '"error":"session_limit"' in reply and "Retry-After" in reply, reply
        finally:
            for raw in held:
                raw.close()


def test_idle_timeout_closes():
    with Server("--idle-timeout", "1") as s:
        async def run():
            c = await Client.connect(s)
            await c.hello(64, 64)
            try:
                while True:
                    await c.recv(timeout=10)
            except websockets.exceptions.ConnectionClosed as e:
                assert e.rcvd.code == 1001, e
        asyncio.run(run())


def test_volumes_only_from_data_directories():
    with Server() as s:
        for v in ("../../etc/passwd", "/etc/passwd", "../unit/load_memory_test.sh", "nonexistent.nrrd"):
            status, _, body = http(s, "/api/render", "POST", json.dumps({"volume": v}).encode())
            assert status == 404, (v, status, body[:200])
            assert json.loads(body)["error"] == "volume_error"
        status, _, body = http(s, "/api/render", "POST", json.dumps({"volume": "nucleon.nhdr", "image": {"width": 16, "height": 16}}).encode())
        assert status == 200, body


def test_crafted_nrrd_pattern_is_refused_and_the_server_lives():
    # Regression: `data file: q.%s 1 9 1` reached snprintf with a user-written format (SIGSEGV).
    with tempfile.TemporaryDirectory() as tmp:
        pathlib.Path(tmp, "evil.nhdr").write_text(
            "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 9\nencoding: raw\ndata file: q.%s 1 9 1\n")
        info = subprocess.run([PEAKCAST, "info", f"{tmp}/evil.nhdr"], capture_output=True, text=True)
        assert info.returncode == 2 and "data file pattern" in info.stderr, (info.returncode, info.stderr)
        with Server("--data", tmp) as s:
            status, _, body = http(s, "/api/render", "POST", json.dumps({"volume": "evil.nhdr"}).encode())
            assert status == 404 and "data file pattern" in json.loads(body)["message"], (status, body)

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 64)
                await c.send({"type": "volume", "volume": "evil.nhdr"})
                e = await c.next_text("error")
                assert e["code"] == "volume_error" and "data file pattern" in e["message"], e
                await c.close()
            asyncio.run(ws())
            assert s.alive() and http(s, "/api/health")[0] == 200


def test_binds_loopback_by_default():
    with Server() as s:
        assert s.host == "127.0.0.1"


def test_body_and_image_caps():
    with Server() as s:
        # A body announced over the 1 MiB cap is refused before it is read.
        import socket
        with socket.create_connection((s.host, s.port)) as raw:
            raw.sendall(f"POST /api/render HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: {2 << 20}\r\n\r\n".encode())
            reply = raw.recv(4096).decode()
            assert reply.startswith("HTTP/1.1 413") and '"error":"too_large"' in reply, reply
        status, _, body = http(s, "/api/render", "POST", json.dumps({"volume": "heptane_151", "image": {"width": 9000, "height": 10}}).encode())
        assert status == 400 and b"image.width" in body, body
        status, _, body = http(s, "/api/render", "POST", b"not json")
        assert status == 400 and json.loads(body)["error"] == "bad_scene"
        assert http(s, "/api/nothing")[0] == 404
        assert http(s, "/../../etc/passwd")[0] in (400, 404)
        assert http(s, "/api/render")[0] == 405


def test_gpu_budget_refuses_a_second_volume_and_sessions_go_on():
    # heptane is 3.3 MiB: a 4 MiB budget holds it and refuses the 0.36 MiB headsq beside it.
    with Server("--gpu-budget-mib", "4") as s:
        async def run():
            c = await Client.connect(s)
            await c.hello(96, 96)
            await c.next_frame(final=True)
            await c.send({"type": "volume", "volume": "headsq/quarter.nhdr"})
            e = await c.next_text("error")
            assert e["code"] == "volume_error" and "budget" in e["message"], e
            await c.send({"type": "camera", "camera": {"eye": [75, 75, 400], "center": [75, 75, 75], "up": [0, 1, 0]}})
            await c.next_frame(final=True)
            await c.close()
        asyncio.run(run())
        status, _, body = http(s, "/api/render", "POST", json.dumps({"volume": "headsq/quarter.nhdr"}).encode())
        assert status == 404 and b"budget" in body, body[:200]


if __name__ == "__main__":
    run_tests([test_crafted_nrrd_pattern_is_refused_and_the_server_lives, test_token, test_foreign_origin_refused, test_session_cap_gives_503_with_a_reason,
               test_idle_timeout_closes, test_volumes_only_from_data_directories, test_binds_loopback_by_default,
               test_body_and_image_caps, test_gpu_budget_refuses_a_second_volume_and_sessions_go_on])
