#!/usr/bin/env python3
"""WebSocket streaming against a real server: first frame, still == CLI render, progressive
quality, coalescing, flow control with a non-acking client, hostile messages, disconnects."""
import asyncio, json, os, pathlib, subprocess, sys, tempfile, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

SERVER = None
SCENE_CAMERA = {"eye": [75, -160, 230], "center": [75, 75, 75], "up": [0, 0, 1], "fov_y": 30}


async def test_hello_then_frames_decode():
    c = await Client.connect(SERVER)
    w = await c.hello(200, 150)
    assert w["volume"]["id"] == "heptane_151" and len(w["volume"]["histogram"]) == 1024
    assert "peaks" in w["capabilities"]["classification"]
    first = await c.next_frame()
    img = decode_image(first["image"])
    assert img.size == (first["width"], first["height"])
    final = first if first["final"] else await c.next_frame(final=True)
    assert (final["width"], final["height"]) == (200, 150) and final["quality"] >= 95
    # The default view of heptane (default TF over the value range) shows something: not all black.
    extrema = decode_image(final["image"]).getextrema()
    assert max(hi for _, hi in extrema) >= 32, f"the default view is black: {extrema}"
    stats = [t for t in c.texts if t["type"] == "stats"]
    # The variant names the backend that drew it (auto: the CPU backend on llvmpipe).
    assert w["backend"] in ("gl", "cpu") and w["gl_renderer"].startswith(w["backend"] + ": ")
    assert stats and stats[-1]["variant"].startswith("cpu" if w["backend"] == "cpu" else "frag")
    await c.close()


async def test_interactive_frames_shrink_to_hold_their_budget():
    # A budget no frame can meet: after the first interactive frame's time is known, the next
    # ones are rendered at half the interactive scale (the most they are reduced), finals never.
    c = await Client.connect(SERVER)
    await c.hello(240, 180)
    await c.next_frame(final=True)
    await c.send({"type": "quality", "interactive_ms": 0.001})
    await c.next_frame(final=True)  # a quality change re-sends the still
    widths, moving = [], True

    async def move():  # input every 20 ms until four interactive frames came (slow builds: TSan)
        cam, i = dict(SCENE_CAMERA), 0
        while moving:
            i += 1
            cam = dict(cam, eye=[75 + 10 * (i % 20), -160, 230])
            await c.send({"type": "camera", "camera": cam})
            await asyncio.sleep(0.02)

    mover = asyncio.create_task(move())
    deadline = time.time() + 60
    while len(widths) < 4 and time.time() < deadline:
        f = await c.next_frame(timeout=60)
        if not f["final"]:
            widths.append((f["width"], f["height"]))
    moving = False
    await mover
    assert widths and widths[0][0] <= 120, widths
    assert widths[-1] == (60, 45), widths
    assert all(w >= 60 for w, _ in widths), widths
    last = await c.next_frame(final=True)
    assert (last["width"], last["height"]) == (240, 180)
    await c.close()


async def test_still_frame_matches_cli_render():
    tf = {"points": [[0, 0, 0, 0, 0], [90, 0.2, 0.5, 1.0, 0.04], [140, 0.2, 0.5, 1, 0], [199, 1, 0.1, 0, 0],
                     [200, 1, 0.1, 0, 0.9], [201, 1, 0.1, 0, 0], [255, 1, 1, 1, 0]]}
    render = {"classification": "peaks", "shading": True}
    c = await Client.connect(SERVER)
    await c.hello(256, 192, state={"camera": SCENE_CAMERA, "tf": tf, "render": render})
    await c.send({"type": "quality", "final_format": "png"})
    frame = await c.next_frame(final=True)
    while not frame["png"]:
        frame = await c.next_frame(final=True)
    await c.close()
    with tempfile.TemporaryDirectory() as tmp:
        scene = {"volume": str(DATA / "heptane_151.nrrd"), "camera": SCENE_CAMERA, "tf": tf, "render": render,
                 "image": {"width": 256, "height": 192}}
        p = pathlib.Path(tmp) / "s.json"
        p.write_text(json.dumps(scene))
        subprocess.run([PEAKCAST, "render", str(p), "-o", f"{tmp}/cli.png"], check=True, capture_output=True)
        value = psnr(decode_image(frame["image"]), Image.open(f"{tmp}/cli.png"))
    print(f"  still frame vs CLI render: PSNR {value:.1f} dB")
    # The same scene through the same renderer and the same 8-bit conversion: identical pixels.
    assert value == 200.0, f"the streamed PNG differs from the CLI render ({value:.1f} dB)"


async def test_progressive_interactive_then_final():
    c = await Client.connect(SERVER)
    await c.hello(240, 180)
    await c.next_frame(final=True)
    await c.send({"type": "quality", "interactive_ms": 0})  # a fixed interactive scale (no budget)
    await c.next_frame(final=True)  # a quality change re-sends the still
    cam = dict(SCENE_CAMERA)
    for i in range(5):
        cam = dict(cam, eye=[75 + 20 * i, -160, 230])
        await c.send({"type": "camera", "camera": cam})
        await asyncio.sleep(0.02)
    f = await c.next_frame()
    assert f["interactive"] and not f["final"] and f["width"] == 120 and f["quality"] == 70, f
    last = await c.next_frame(final=True)
    assert last["width"] == 240 and last["quality"] == 95 and last["camera_version"] >= 6
    await c.close()


async def test_fast_input_coalesces():
    c = await Client.connect(SERVER)
    await c.hello(160, 120)
    await c.next_frame(final=True)
    n_before = len(c.frames)
    cam = dict(SCENE_CAMERA)
    for i in range(200):
        cam = dict(cam, eye=[75 + i, -160, 230])
        await c.send({"type": "camera", "camera": cam})
    f = await c.next_frame(final=True)
    assert f["camera_version"] >= 201, f["camera_version"]  # the final frame shows the newest camera
    frames = len(c.frames) - n_before
    print(f"  200 camera messages -> {frames} frames")
    assert frames < 100
    await c.close()


async def test_non_acking_client_gets_two_frames_and_costs_nothing():
    c = await Client.connect(SERVER, ack=False)
    await c.hello(320, 240)
    cam = dict(SCENE_CAMERA)

    async def spam(seconds, i):
        end = time.time() + seconds
        while time.time() < end:
            i += 1
            await c.send({"type": "camera", "camera": dict(cam, eye=[75 + (i % 50), -160, 230])})
            try:
                await asyncio.wait_for(c.recv(), 0.01)
            except asyncio.TimeoutError:
                pass
        return i

    async def drain():
        try:
            while True:
                await asyncio.wait_for(c.recv(), 1.0)
        except asyncio.TimeoutError:
            pass

    # Warm up until the two unacknowledged frames are out: the session's render
    # buffers and encoder exist from then on, so what follows measures only the
    # cost of a client that keeps talking and never acknowledges.
    i = await spam(1.5, 0)
    await drain()
    assert len(c.frames) == 2, len(c.frames)
    rss0 = SERVER.rss_kib()
    i = await spam(4, i)
    await drain()
    rss1 = SERVER.rss_kib()
    print(f"  {i} camera messages, {len(c.frames)} frames without acks; server RSS {rss0} -> {rss1} KiB")
    assert len(c.frames) == 2, len(c.frames)
    # A sanitizer's shadow memory and allocator bookkeeping grow with any work;
    # the bound there only catches a per-message leak of frames.
    bound = 20 * 1024 if os.environ.get("PEAKCAST_SANITIZER", "none") == "none" else 64 * 1024
    assert rss1 - rss0 < bound, f"server memory grew by {rss1 - rss0} KiB with a non-acking client"
    # Acking resumes the stream, with the newest state.
    for f in c.frames:
        await c.send({"type": "ack", "frame": f["id"]})
    c.ack = True
    f = await c.next_frame(final=True)
    assert f["camera_version"] == i + 1
    await c.close()


HOSTILE = [
    "not json", "", "[]", "42", "null", '{"type": 7}', '{"no": "type"}', '{"type": "explode"}',
    '{"type": "camera"}', '{"type": "camera", "camera": {}}', '{"type": "camera", "camera": {"eye": [0,0,0], "center": [0,0,0]}}',
    '{"type": "camera", "camera": {"eye": [0,0,1], "center": [0,0,0], "up": [0,0,1]}}',
    '{"type": "camera", "camera": {"eye": ["a",0,1], "center": [0,0,0]}}',
    '{"type": "camera", "camera": {"eye": [1e999,0,1], "center": [0,0,0]}}',
    '{"type": "camera", "camera": {"eye": [NaN,0,1], "center": [0,0,0]}}',
    '{"type": "camera", "camera": {"eye": [0,0,1], "center": [0,0,0], "fov_y": -5}}',
    '{"type": "tf"}', '{"type": "tf", "tf": {"points": []}}', '{"type": "tf", "tf": {"points": [[1,0,0,0,0],[0,1,1,1,1]]}}',
    '{"type": "tf", "tf": {"points": [[0,0,0,0,2]]}}', '{"type": "tf", "tf": {"points": [[0,0,0,0,0.5]]}, "version": -1}',
    '{"type": "tf", "tf": {"points": "many"}}', '{"type": "render", "render": {"step": 0}}',
    '{"type": "render", "render": {"step": 1e-12}}', '{"type": "render", "render": {"classification": "magic"}}',
    '{"type": "render", "render": {"max_peaks": 99}}', '{"type": "render", "render": {"bogus": true}}',
    '{"type": "render"}', '{"type": "quality", "interactive_scale": 5}',
    '{"type": "quality", "interactive_ms": -1}', '{"type": "quality", "interactive_ms": 1001}',
    '{"type": "quality", "interactive_ms": "fast"}', '{"type": "quality", "final_format": "gif"}',
    '{"type": "viewport", "width": 0, "height": 10}', '{"type": "viewport", "width": 100000, "height": 100000}',
    '{"type": "viewport", "width": 8000, "height": 8000, "dpr": 4}', '{"type": "viewport", "width": 10, "height": 10, "dpr": 0}',
    '{"type": "volume", "volume": "../../etc/passwd"}', '{"type": "volume", "volume": "/etc/passwd"}',
    '{"type": "volume", "volume": "nope.nrrd"}', '{"type": "volume"}', '{"type": "ack"}', '{"type": "ack", "frame": -1}',
    '{"type": "ack", "frame": "x"}', '{"type": "ping", "id": 5}', '{"type": "hello", "viewport": {"width": 10, "height": 10}}',
    '{"type": "camera", "camera": {"eye": [0,0,1], "center": [0,0,0]}, "extra": 1}',
    '{"type": "tf", "tf": {"points": [[0,0,0,0,0]], "opacity_unit": -1}}', '{"type": "render", "render": {"filter": 3}}',
    '{"type": "render", "render": {"sampling": "spiral"}}', '{"type": "render", "render": {"virtual_samples": 5}}',
    '{"type": "render", "render": {"s_k": 0}}', '{"type": "render", "render": {"ray_texture": {"mapping": "view"}}}',
    '{"type": "render", "render": {"early_termination": 2}}', '{"type": "render", "render": {"peak_table_bins": 5}}',
    '{"type": "ping", "id": "' + "x" * 100 + '"}', '{"type":"tf","tf":{"points":[' + ",".join(["[0,0,0,0,0]"] * 3) + ']}}',
    '{"type": "camera", "camera": {"eye": [0,0,1], "center": [0,0,0], "projection": "orthographic"}}',
    '{"type": "tf", "tf": {"points": [[0,0,0,0,0]]}, "version": 99999999999}',
    '{"type": "viewport", "width": 1.5, "height": 10}', '{"type": "quality", "final_quality": 101}',
    "{" * 1000, '"just a string"', '{"type": "camera", "camera": null}', '{"type": null}',
]


async def test_hostile_messages_get_errors_and_the_session_renders():
    msgs = list(HOSTILE)
    msgs += ['{"type": "tf", "tf": {"points": [[%d,0,0,0,0]]}, "bad": %d}' % (i, i) for i in range(100 - len(msgs) - 1)]
    msgs.append("x" * (300 * 1024))  # over the 256 KiB message cap: error, then the socket closes
    c = await Client.connect(SERVER)
    await c.hello(160, 120)
    await c.next_frame(final=True)
    errors = 0
    for m in msgs[:-1]:
        await c.send(m)
        try:
            reply = await c.next_text("error", timeout=10)
        except TimeoutError:
            raise AssertionError(f"no error reply to {m[:120]!r}")
        assert reply["code"] in ("bad_json", "bad_message", "unknown_type", "volume_error", "too_large"), reply
        errors += 1
    # Still renders after all of that.
    await c.send({"type": "camera", "camera": dict(SCENE_CAMERA, eye=[80, -150, 220])})
    f = await c.next_frame(final=True)
    assert f["camera_version"] >= 2
    await c.send(msgs[-1])
    reply = await c.next_text("error")
    assert reply["code"] == "too_large"
    errors += 1
    print(f"  {len(msgs)} hostile messages, {errors} error replies")
    assert len(msgs) == 100 and errors == 100
    await c.send({"type": "camera", "camera": dict(SCENE_CAMERA, eye=[70, -150, 220])})
    await c.next_frame(final=True)
    # Beyond the 4 MiB read cap the server does not read the message: it closes with 1009.
    try:
        await c.send("y" * (5 * 1024 * 1024))
        while True:
            await c.recv(timeout=10)
    except websockets.exceptions.ConnectionClosed as e:
        assert e.rcvd is not None and e.rcvd.code == 1009, e
    assert SERVER.alive()


async def test_message_before_hello_is_refused():
    c = await Client.connect(SERVER)
    await c.send({"type": "camera", "camera": SCENE_CAMERA})
    e = await c.next_text("error")
    assert e["code"] == "no_session"
    await c.send({"type": "ping", "id": "p1"})
    assert (await c.next_text("pong"))["id"] == "p1"
    await c.hello()
    await c.next_frame()
    await c.close()


async def test_disconnect_mid_render():
    for _ in range(5):
        c = await Client.connect(SERVER)
        await c.send({"type": "hello", "viewport": {"width": 1024, "height": 1024}})
        await c.ws.close()
    await asyncio.sleep(1.0)
    status, _, body = http(SERVER, "/api/health")
    assert status == 200 and json.loads(body)["sessions"] == 0, body
    c = await Client.connect(SERVER)
    await c.hello()
    await c.next_frame(final=True)
    await c.close()


async def test_switch_volume_and_budget_refusal():
    c = await Client.connect(SERVER)
    await c.hello()
    await c.next_frame(final=True)
    await c.send({"type": "volume", "volume": "nucleon.nhdr"})
    v = await c.next_text("volume")
    assert v["volume"]["dims"] == [41, 41, 41]
    f = await c.next_frame(final=True)
    assert f["camera_version"] >= 2
    await c.close()


def loading_before(texts, kind, volume):
    """The loading messages for `volume` before the first `kind` message: rising, the last 1."""
    end = next(i for i, m in enumerate(texts) if m["type"] == kind)
    told = [m["fraction"] for m in texts[:end] if m["type"] == "loading"]
    assert all(m["volume"] == volume for m in texts[:end] if m["type"] == "loading"), texts[:end]
    assert told == sorted(told) and all(0 < f <= 1 for f in told), told
    return told


async def test_loading_is_told_before_the_volume():
    c = await Client.connect(SERVER)
    await c.hello(volume="HeadMRVolume.mhd")
    told = loading_before(c.texts, "welcome", "HeadMRVolume.mhd")
    assert told and told[-1] == 1, told
    await c.next_frame(final=True)
    c.texts.clear()
    await c.send({"type": "volume", "volume": "headsq"})
    await c.next_text("volume")
    told = loading_before(c.texts, "volume", "headsq")
    assert told and told[-1] == 1, told
    # A volume already loaded is switched to at once: no loading message.
    c.texts.clear()
    await c.send({"type": "volume", "volume": "HeadMRVolume.mhd"})
    await c.next_text("volume")
    assert loading_before(c.texts, "volume", "HeadMRVolume.mhd") == []
    await c.close()


def main():
    global SERVER
    with Server("--max-sessions", "8") as s:
        SERVER = s
        run_tests([test_hello_then_frames_decode, test_still_frame_matches_cli_render,
                   test_progressive_interactive_then_final, test_interactive_frames_shrink_to_hold_their_budget,
                   test_fast_input_coalesces,
                   test_non_acking_client_gets_two_frames_and_costs_nothing,
                   test_hostile_messages_get_errors_and_the_session_renders, test_message_before_hello_is_refused,
                   test_disconnect_mid_render, test_switch_volume_and_budget_refusal,
                   test_loading_is_told_before_the_volume])


if __name__ == "__main__":
    main()
