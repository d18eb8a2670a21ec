#!/usr/bin/env python3
"""Ray textures over the wire: the stroke message and its acknowledgement, strokes that
change only their disk of the streamed frame, replay on reconnect, PNG ray textures read only from
the data directories (REST and WebSocket), and every refusal."""
import asyncio, json, math, os, pathlib, subprocess, sys, tempfile

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

SERVER = None
PNG_DIR = None  # a second data directory holding the test's PNGs
CAMERA = {"eye": [75, -160, 230], "center": [75, 75, 75], "up": [0, 0, 1], "fov_y": 30}
TF = {"points": [[0, 0, 0, 0, 0], [60, 0.2, 0.5, 1.0, 0.02], [140, 1.0, 0.6, 0.2, 0.3], [255, 1, 1, 1, 0.6]]}
SIZE = 128  # square viewport: a view-aligned disk is round in pixels


def stroke(u, v, radius, value, channel="termination", **kw):
    return {"channel": channel, "center": [u, v], "radius": radius, "value": value, **kw}


async def png_final(c):
    """The next final frame that is a PNG (the quality message asks for PNG stills)."""
    while True:
        f = await c.next_frame(final=True)
        if f["png"]:
            return f


async def viewer(ray_texture):
    c = await Client.connect(SERVER)
    render = {"ray_texture": ray_texture} if ray_texture is not None else {}
    await c.hello(SIZE, SIZE, state={"camera": CAMERA, "tf": TF, "render": render})
    await c.send({"type": "quality", "final_format": "png"})
    return c


def pixels(frame):
    return decode_image(frame["image"]).tobytes()


def disk_changes(a, b, u, v, radius, margin=2.5):
    """Pixels that differ inside the disk and outside it (beyond `margin` pixels of its edge)."""
    inside = outside = 0
    for y in range(SIZE):
        for x in range(SIZE):
            d = math.hypot(x + 0.5 - u * SIZE, y + 0.5 - v * SIZE)
            i = (y * SIZE + x) * 3
            differs = max(abs(a[i + k] - b[i + k]) for k in range(3)) > 1
            if d < radius * SIZE - margin:
                inside += differs
            elif d > radius * SIZE + margin:
                outside += differs
    return inside, outside


async def test_a_stroke_is_acknowledged_and_changes_only_its_disk():
    c = await viewer({"mapping": "view", "size": [64, 64]})
    before = await png_final(c)
    # Termination 0.05 inside the disk: those rays stop almost at once.
    await c.send({"type": "stroke", "seq": 1, "stroke": stroke(0.35, 0.55, 0.2, 0.05)})
    ack = await c.next_text("stroke_ack")
    assert ack["seq"] == 1 and ack["strokes"] == 1, ack
    after = await png_final(c)
    assert after["render_version"] > before["render_version"]
    inside, outside = disk_changes(pixels(before), pixels(after), 0.35, 0.55, 0.2)
    print(f"  pixels changed: {inside} inside the disk, {outside} outside it")
    assert inside > 300 and outside == 0, (inside, outside)
    # The frame's stats: one stroke applied, only its dirty rectangle uploaded (not the 64x64 texture).
    # A frame's stats follow the frame: wait for those of the final one.
    while not any(t["type"] == "stats" and t["frame"] == after["id"] for t in c.texts):
        await c.recv()
    stats = [t for t in c.texts if t["type"] == "stats" and "+raytex:view" in t["variant"]]
    applied = [s for s in stats if s["ray_texture_strokes"] == 1]
    assert applied, stats[-3:]
    assert 0 < applied[0]["ray_texture_texels"] <= 28 * 28, applied[0]
    await c.close()


async def test_strokes_replayed_in_hello_give_the_same_image():
    strokes = [stroke(0.3, 0.4, 0.15, 0.1), stroke(0.6, 0.6, 0.2, 0.25, channel="step", mode="multiply", falloff=0.5),
               stroke(0.7, 0.3, 0.1, 0.5, channel="blend", level=2)]
    live = await viewer({"mapping": "view", "size": [64, 64]})
    await png_final(live)
    for i, s in enumerate(strokes, 1):
        await live.send({"type": "stroke", "seq": i, "stroke": s})
    for i in range(1, 4):
        assert (await live.next_text("stroke_ack"))["seq"] == i
    painted = await png_final(live)
    await live.close()
    # A reconnecting client: its hello carries the texture with every stroke it painted.
    again = await viewer({"mapping": "view", "size": [64, 64], "strokes": strokes})
    welcome = [t for t in again.texts if t["type"] == "welcome"][0]
    assert len(welcome["state"]["render"]["ray_texture"]["strokes"]) == 3
    replayed = await png_final(again)
    await again.close()
    value = psnr(decode_image(painted["image"]), decode_image(replayed["image"]))
    assert value == 200.0, f"replayed strokes differ from painted ones ({value:.1f} dB)"


async def test_bad_strokes_are_refused_and_the_session_goes_on():
    c = await viewer(None)
    await c.next_frame(final=True)
    await c.send({"type": "stroke", "seq": 1, "stroke": stroke(0.5, 0.5, 0.1, 0.5)})
    e = await c.next_text("error")
    assert e["code"] == "bad_message" and "no ray texture" in e["message"], e
    await c.send({"type": "render", "render": {"ray_texture": {"mapping": "volume", "size": [32, 32]}}})
    bad = [({"type": "stroke", "seq": 2, "stroke": stroke(0.5, 0.5, 0.0, 0.5)}, "stroke.stroke.radius"),
           ({"type": "stroke", "seq": 2, "stroke": stroke(0.5, 0.5, 1.5, 0.5)}, "stroke.stroke.radius"),
           ({"type": "stroke", "seq": 2, "stroke": stroke(0.5, 0.5, 0.1, 0.5, channel="opacity")}, "stroke.stroke.channel"),
           ({"type": "stroke", "seq": 2, "stroke": stroke(1.5, 0.5, 0.1, 0.5)}, "stroke.stroke.center"),
           ({"type": "stroke", "seq": 2, "stroke": stroke(0.5, 0.5, 0.1, 9.0, channel="step")}, "stroke.stroke.value"),
           ({"type": "stroke", "stroke": stroke(0.5, 0.5, 0.1, 0.5)}, "stroke.seq"),
           ({"type": "stroke", "seq": -1, "stroke": stroke(0.5, 0.5, 0.1, 0.5)}, "stroke.seq"),
           ({"type": "stroke", "seq": 2}, "stroke.stroke"),
           ({"type": "stroke", "seq": 2, "stroke": stroke(0.5, 0.5, 0.1, 0.5), "brush": 1}, "stroke.brush")]
    for msg, key in bad:
        await c.send(msg)
        e = await c.next_text("error")
        assert e["code"] == "bad_message" and key in e["message"], (msg, e)
    # NaN is not JSON: refused as such.
    await c.send('{"type": "stroke", "seq": 2, "stroke": {"channel": "step", "center": [NaN, 0.5], "radius": 0.1, "value": 1}}')
    assert (await c.next_text("error"))["code"] == "bad_json"
    await c.send({"type": "stroke", "seq": 2, "stroke": stroke(0.5, 0.5, 0.1, 0.5)})
    assert (await c.next_text("stroke_ack"))["strokes"] == 1
    await c.send({"type": "ping", "id": "still here"})
    assert (await c.next_text("pong"))["id"] == "still here"
    await c.close()


def write_png(path, size, rgb, mode="RGB"):
    Image.new(mode, size, rgb).save(path)


def scene_with(png, width=SIZE, height=SIZE):
    return {"volume": "heptane_151", "camera": CAMERA, "tf": TF, "image": {"width": width, "height": height},
            "render": {"ray_texture": {"mapping": "view", "png": png}}}


def test_png_ray_texture_over_rest_equals_the_cli():
    # Left half: termination 10/255 (rays stop early); right half: the defaults (128, 254, 128).
    img = Image.new("RGB", (32, 32), (128, 254, 128))
    for y in range(32):
        for x in range(16):
            img.putpixel((x, y), (128, 10, 128))
    img.save(PNG_DIR / "half.png")
    status, headers, body = http(SERVER, "/api/render", "POST", json.dumps(scene_with("half.png")).encode())
    assert status == 200, body[:300]
    assert "+raytex:view" in headers["X-Variant"], headers["X-Variant"]
    with tempfile.TemporaryDirectory() as tmp:
        scene = scene_with("half.png")
        scene["volume"] = str(DATA / "heptane_151.nrrd")
        (pathlib.Path(tmp) / "half.png").write_bytes((PNG_DIR / "half.png").read_bytes())
        (pathlib.Path(tmp) / "s.json").write_text(json.dumps(scene))
        subprocess.run([PEAKCAST, "render", f"{tmp}/s.json", "-o", f"{tmp}/cli.png"], check=True, capture_output=True)
        cli = Image.open(f"{tmp}/cli.png")
        assert psnr(decode_image(body), cli) == 200.0, "REST and CLI differ"
        # Against no texture: the right half (defaults) is unchanged, the left half changes.
        plain = dict(scene)
        plain["render"] = {}
        (pathlib.Path(tmp) / "p.json").write_text(json.dumps(plain))
        subprocess.run([PEAKCAST, "render", f"{tmp}/p.json", "-o", f"{tmp}/plain.png"], check=True, capture_output=True)
        a, b = cli.convert("RGB").tobytes(), Image.open(f"{tmp}/plain.png").convert("RGB").tobytes()
    left = sum(a[i] != b[i] for y in range(SIZE) for x in range(0, SIZE // 2 - 4) for i in [(y * SIZE + x) * 3 + 1])
    right = sum(a[i] != b[i] for y in range(SIZE) for x in range(SIZE // 2 + 4, SIZE) for i in [(y * SIZE + x) * 3 + 1])
    print(f"  PNG texture: {left} pixels changed in the left half, {right} in the right")
    assert left > 300 and right == 0, (left, right)


def test_png_ray_textures_are_refused_outside_the_data_directories_or_malformed():
    write_png(PNG_DIR / "wide.png", (2049, 1), (128, 254, 128))
    write_png(PNG_DIR / "mid.png", (8, 8), (128, 254, 128))
    write_png(PNG_DIR / "grey.png", (8, 8), 128, mode="L")
    (PNG_DIR / "text.png").write_text("not an image")
    Image.new("RGB", (8, 8)).save(PNG_DIR / "photo.jpg")
    with tempfile.TemporaryDirectory() as outside:
        write_png(pathlib.Path(outside) / "ok.png", (8, 8), (128, 254, 128))
        os.symlink(pathlib.Path(outside) / "ok.png", PNG_DIR / "link.png")
        try:
            cases = [(f"{outside}/ok.png", "outside"), ("../../etc/passwd", "outside"),
                     ("link.png", "data directories"), ("missing.png", "no such file"),
                     ("wide.png", "wrong size"), ("grey.png", "channel"), ("text.png", "not PNG"),
                     ("photo.jpg", "not PNG")]
            for png, words in cases:
                status, _, body = http(SERVER, "/api/render", "POST", json.dumps(scene_with(png)).encode())
                msg = json.loads(body)
                assert status == 400 and msg["error"] == "bad_scene" and words in msg["message"], (png, status, msg)
            status, _, body = http(SERVER, "/api/render", "POST",
                                   json.dumps(dict(scene_with("ok.png"), render={"ray_texture": {
                                       "mapping": "view", "png": "ok.png", "size": [8, 8]}})).encode())
            assert status == 400 and "not both" in json.loads(body)["message"]

            async def over_ws():
                c = await viewer(None)
                await c.next_frame(final=True)
                await c.send({"type": "render", "render": {"ray_texture": {"mapping": "view", "png": f"{outside}/ok.png"}}})
                e = await c.next_text("error")
                assert e["code"] == "bad_message" and "render.ray_texture.png" in e["message"], e
                await c.send({"type": "render", "render": {"ray_texture": {"mapping": "view", "png": "wide.png"}}})
                assert "wrong size" in (await c.next_text("error"))["message"]
                await c.send({"type": "render", "render": {"ray_texture": {"mapping": "volume", "png": "mid.png"}}})
                await c.send({"type": "stroke", "seq": 1, "stroke": stroke(0.5, 0.5, 0.2, 0.5)})  # strokes over a PNG
                assert (await c.next_text("stroke_ack"))["strokes"] == 1
                f = await c.next_frame(final=True)
                assert f["render_version"] >= 3
                await c.close()

            async def in_hello():
                # A hello whose state names a PNG outside the data directories: refused, and the
                # connection may say hello again.
                c = await Client.connect(SERVER)
                bad = {"ray_texture": {"mapping": "view", "png": f"{outside}/ok.png"}}
                await c.send({"type": "hello", "viewport": {"width": SIZE, "height": SIZE}, "state": {"render": bad}})
                e = await c.next_text("error")
                assert e["code"] == "bad_message" and "outside" in e["message"], e
                w = await c.hello(SIZE, SIZE, state={"render": {"ray_texture": {"mapping": "view", "png": "mid.png"}}})
                assert w["state"]["render"]["ray_texture"]["png"] == "mid.png", w["state"]["render"]
                await c.next_frame(final=True)
                await c.close()

            asyncio.run(over_ws())
            asyncio.run(in_hello())
        finally:
            (PNG_DIR / "link.png").unlink()


def main():
    global SERVER, PNG_DIR
    with tempfile.TemporaryDirectory() as tmp:
        PNG_DIR = pathlib.Path(tmp)
        with Server("--data", str(PNG_DIR)) as s:
            SERVER = s
            run_tests([test_a_stroke_is_acknowledged_and_changes_only_its_disk,
                       test_strokes_replayed_in_hello_give_the_same_image,
                       test_bad_strokes_are_refused_and_the_session_goes_on,
                       test_png_ray_texture_over_rest_equals_the_cli,
                       test_png_ray_textures_are_refused_outside_the_data_directories_or_malformed])


if __name__ == "__main__":
    main()
