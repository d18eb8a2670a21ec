#!/usr/bin/env python3
"""REST and shared resources: routes, REST render == CLI render, 16 sessions on one GPU copy,
/metrics as Prometheus text."""
import asyncio, io, json, pathlib, re, subprocess, sys, tempfile

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

SERVER = None
SCENE = {"volume": "heptane_151", "image": {"width": 200, "height": 160},
         "camera": {"eye": [75, -160, 230], "center": [75, 75, 75], "up": [0, 0, 1], "fov_y": 30},
         "tf": {"points": [[0, 0, 0, 0, 0], [90, 0.2, 0.5, 1.0, 0.04], [140, 0.2, 0.5, 1, 0], [199, 1, 0.1, 0, 0],
                           [200, 1, 0.1, 0, 0.9], [201, 1, 0.1, 0, 0], [255, 1, 1, 1, 0]]},
         "render": {"classification": "peaks", "shading": True, "filter": "tricubic"}}


def test_health_and_volumes():
    status, _, body = http(SERVER, "/api/health")
    h = json.loads(body)
    assert status == 200 and h["status"] == "ok" and h["gl_renderer"], h
    assert h["stills_queued"] == 0 and h["max_queued_stills"] >= 1, h
    status, _, body = http(SERVER, "/api/volumes")
    v = json.loads(body)
    assert v["default"] == "heptane_151" and v["volumes"][0]["dims"] == [151, 151, 151]
    assert v["volumes"][0]["units"] == "units", "heptane's NRRD names no unit: lengths in units"
    status, _, body = http(SERVER, "/api/volumes/heptane_151")
    info = json.loads(body)
    assert len(info["histogram"]) == 1024 and sum(info["histogram"]) == 151 ** 3
    assert http(SERVER, "/api/volumes/nope")[0] == 404


def test_rest_render_equals_cli_render():
    status, headers, png = http(SERVER, "/api/render", "POST", json.dumps(SCENE).encode())
    assert status == 200 and headers["Content-Type"] == "image/png", (status, png[:200])
    assert float(headers["X-Render-Ms"]) > 0 and "peaks" in headers["X-Variant"]
    with tempfile.TemporaryDirectory() as tmp:
        scene = dict(SCENE, volume=str(DATA / "heptane_151.nrrd"))
        pathlib.Path(tmp, "s.json").write_text(json.dumps(scene))
        subprocess.run([PEAKCAST, "render", f"{tmp}/s.json", "-o", f"{tmp}/cli.png"], check=True, capture_output=True)
        value = psnr(decode_image(png), Image.open(f"{tmp}/cli.png"))
    print(f"  REST vs CLI: PSNR {value:.1f} dB")
    assert value == 200.0, "REST and CLI render the same scene with the same code: identical pixels"


def test_rest_jpeg_and_refusals():
    status, headers, jpg = http(SERVER, "/api/render?format=jpeg&quality=80", "POST", json.dumps(SCENE).encode())
    assert status == 200 and headers["Content-Type"] == "image/jpeg"
    assert decode_image(jpg).size == (200, 160)
    status, headers, jpg = http(SERVER, "/api/render", "POST", json.dumps(SCENE).encode(), {"Accept": "image/jpeg"})
    assert headers["Content-Type"] == "image/jpeg"
    for q in ("format=gif", "quality=0", "quality=abc"):
        assert http(SERVER, "/api/render?" + q, "POST", json.dumps(SCENE).encode())[0] == 400, q
    # Differential, adaptive and virtual samples render; ray textures are refused by name.
    for ok in ({"sampling": "differential", "s_k": 2}, {"adaptive": True}, {"virtual_samples": 3}):
        status, _, _ = http(SERVER, "/api/render", "POST", json.dumps(dict(SCENE, render=ok)).encode())
        assert status == 200, (ok, status)
    for bad, key in (({"s_k": -1}, b"render.s_k"), ({"virtual_samples": 5}, b"render.virtual_samples")):
        status, _, body = http(SERVER, "/api/render", "POST", json.dumps(dict(SCENE, render=bad)).encode())
        assert status == 400 and key in body, (bad, status, body)


def test_rest_stills_honour_the_clip():
    """render.clip over REST: a covering box changes no pixel; a plane through the middle does."""
    status, _, plain = http(SERVER, "/api/render", "POST", json.dumps(SCENE).encode())
    covering = dict(SCENE, render=dict(SCENE["render"], clip={"box": [[-5, -5, -5], [160, 160, 160]]}))
    status, _, same = http(SERVER, "/api/render", "POST", json.dumps(covering).encode())
    assert status == 200 and psnr(decode_image(plain), decode_image(same)) == 200.0
    half = dict(SCENE, render=dict(SCENE["render"], clip={"plane": {"point": [75, 75, 75], "normal": [1, 0, 0]}}))
    status, _, cut = http(SERVER, "/api/render", "POST", json.dumps(half).encode())
    assert status == 200 and psnr(decode_image(plain), decode_image(cut)) < 30
    bad = dict(SCENE, render=dict(SCENE["render"], clip={"plane": {"point": [0, 0, 0], "normal": [0, 0, 0]}}))
    status, _, body = http(SERVER, "/api/render", "POST", json.dumps(bad).encode())
    assert status == 400 and b"render.clip.plane.normal" in body, body


def test_rest_projections_equal_the_cli():
    """classification mip, minip and average over REST: the variant says so, the picture is the
    CLI's, and each differs from the others."""
    pictures = {}
    for c in ("mip", "minip", "average"):
        scene = dict(SCENE, render={"classification": c}, tf={"points": [[0, 0, 0, 0, 0], [255, 1, 1, 1, 1]]})
        status, headers, png = http(SERVER, "/api/render", "POST", json.dumps(scene).encode())
        assert status == 200 and "+" + c in headers["X-Variant"], (c, status, png[:200])
        with tempfile.TemporaryDirectory() as tmp:
            pathlib.Path(tmp, "s.json").write_text(json.dumps(dict(scene, volume=str(DATA / "heptane_151.nrrd"))))
            subprocess.run([PEAKCAST, "render", f"{tmp}/s.json", "-o", f"{tmp}/cli.png"], check=True, capture_output=True)
            assert psnr(decode_image(png), Image.open(f"{tmp}/cli.png")) == 200.0, c
        pictures[c] = decode_image(png)
    assert psnr(pictures["mip"], pictures["average"]) < 30 and psnr(pictures["average"], pictures["minip"]) < 30


def test_sixteen_sessions_share_one_gpu_copy():
    async def run():
        clients = [await Client.connect(SERVER) for _ in range(16)]
        for c in clients:
            await c.hello(96, 72)
        for c in clients:
            f = await c.next_frame(final=True)
            assert decode_image(f["image"]).size == (96, 72)
        status, _, text = http(SERVER, "/metrics")
        metrics = parse_prometheus(text.decode())
        assert metrics[("peakcast_sessions", "")] == 16, metrics.get(("peakcast_sessions", ""))
        assert metrics[("peakcast_gpu_volumes", "")] == 1
        # The backend's copy: the GL texture (151^3 bytes of u8), or none on the CPU backend,
        # which reads integer voxels where the volume holds them.
        status, _, health = http(SERVER, "/api/health")
        backend = json.loads(health)["backend"]
        assert metrics[("peakcast_gpu_volume_bytes", "")] == (151 ** 3 if backend == "gl" else 0), backend
        for c in clients:
            await c.close()
    asyncio.run(run())


LINE = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{([a-zA-Z_][a-zA-Z0-9_]*="[^"]*"(,[a-zA-Z_][a-zA-Z0-9_]*="[^"]*")*)?\})? (-?[0-9.e+-]+|\+Inf|NaN)$')


def parse_prometheus(text):
    """Strict enough: every line is a comment (HELP/TYPE) or `name{labels} value`."""
    out, types = {}, {}
    for line in text.splitlines():
        if line.startswith("# HELP "):
            continue
        if line.startswith("# TYPE "):
            _, _, name, kind = line.split(" ", 3)
            assert kind in ("counter", "gauge", "histogram"), line
            types[name] = kind
            continue
        m = LINE.match(line)
        assert m, f"not Prometheus text: {line!r}"
        name = m.group(1)
        base = re.sub(r"_(bucket|sum|count)$", "", name)
        assert name in types or base in types, f"no TYPE for {name}"
        out[(name, m.group(3) or "")] = float(m.group(5))
    return out


def test_metrics_parse_as_prometheus_text():
    status, headers, text = http(SERVER, "/metrics")
    assert status == 200 and headers["Content-Type"].startswith("text/plain")
    m = parse_prometheus(text.decode())
    assert m[("peakcast_frames_sent_total", 'kind="final"')] >= 16
    assert any(k[0] == "peakcast_input_to_sent_ms_bucket" for k in m)
    assert any(k[0] == "peakcast_render_ms_count" for k in m)


def test_static_client_is_served():
    status, headers, body = http(SERVER, "/")
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    # The docs the client's controls link to, as text; nothing else beside them.
    status, headers, body = http(SERVER, "/docs/scenes.md")
    assert status == 200 and headers["Content-Type"].startswith("text/plain") and b"### `render`" in body
    assert http(SERVER, "/docs/nope.md")[0] == 404
    assert http(SERVER, "/docs/../CMakeLists.txt")[0] in (400, 404)
    assert http(SERVER, "/docs/../README.md")[0] in (400, 404)


def probe(body, pixel):
    return http(SERVER, "/api/probe", "POST", json.dumps(dict(body, pixel=pixel)).encode())


def test_probe_over_rest_and_websocket():
    # The centre of the heptane view lands on the plume's peak surface (value 200) inside the box.
    status, _, body = probe(SCENE, [100, 80])
    answer = json.loads(body)
    assert status == 200 and answer["hit"], (status, body)
    assert all(0 <= c <= 150 for c in answer["position"]), answer
    assert answer["opacity"] >= 0.5 and answer["distance"] > 0, answer
    # The probe lies on the pixel's ray: from the eye, along the direction to the hit point, the
    # distance is the eye-to-point length (perspective camera).
    eye = SCENE["camera"]["eye"]
    length = sum((p - e) ** 2 for p, e in zip(answer["position"], eye)) ** 0.5
    assert abs(length - answer["distance"]) < 1e-6 * length, (length, answer)
    # A corner of a wide view misses the box: no hit, nulls.
    wide = dict(SCENE, camera=dict(SCENE["camera"], fov_y=90))
    status, _, body = probe(wide, [0, 0])
    miss = json.loads(body)
    assert status == 200 and miss == {"hit": False, "position": None, "value": None, "distance": None,
                                      "opacity": 0.0, "pick": "half"}, miss
    # This ray crosses only haze the TF gives opacity below 0.05 (at most 0.04): no visible
    # surface, so the default pick falls back to the half-opacity point and says so.
    assert answer["pick"] == "half" and answer["value"] < 90, answer
    status, _, body = probe(dict(SCENE, pick="half"), [100, 80])
    half = json.loads(body)
    assert status == 200 and half == answer, (half, answer)
    # With denser haze (0.2 at 90) the default pick is the first surface, nearer the eye than the
    # half-opacity point, at a value the TF gives at least 0.05.
    dense = dict(SCENE, tf={"points": [[0, 0, 0, 0, 0], [90, 0.2, 0.5, 1.0, 0.2]] + SCENE["tf"]["points"][2:]})
    surface = json.loads(probe(dense, [100, 80])[2])
    dense_half = json.loads(probe(dict(dense, pick="half"), [100, 80])[2])
    assert surface["pick"] == "surface" and surface["value"] >= 90 * 0.05 / 0.2, surface
    assert dense_half["pick"] == "half" and dense_half["distance"] > surface["distance"], (dense_half, surface)
    # The viewer's probe message in the same state answers the same.
    async def run():
        c = await Client.connect(SERVER)
        state = {k: SCENE[k] for k in ("camera", "tf", "render")}
        await c.hello(200, 160, state=state)
        await c.send({"type": "probe", "id": 7, "pixel": [100, 80]})
        m = await c.next_text("probe")
        assert m["id"] == 7 and {k: m[k] for k in answer} == answer, (m, answer)
        await c.send({"type": "probe", "id": 9, "pixel": [100, 80], "pick": "half"})
        m = await c.next_text("probe")
        assert {k: m[k] for k in half} == half, (m, half)
        await c.send({"type": "probe", "id": 10, "pixel": [100, 80], "pick": "middle"})
        e = await c.next_text("error")
        assert e["code"] == "bad_message" and "probe.pick" in e["message"], e
        await c.send({"type": "probe", "id": 8, "pixel": [200, 0]})  # one past the right edge
        e = await c.next_text("error")
        assert e["code"] == "bad_message" and "outside the 200 x 160 image" in e["message"], e
        await c.send({"type": "probe", "pixel": [1.5, 0]})
        e = await c.next_text("error")
        assert e["code"] == "bad_message" and "probe.pixel" in e["message"], e
        await c.send({"type": "ping", "id": "still here"})
        assert (await c.next_text("pong"))["id"] == "still here"
        await c.close()
    asyncio.run(run())


def test_probe_refusals():
    assert http(SERVER, "/api/probe")[0] == 405
    for body, code, words in ((b"not json", 400, b"parse"), (b"[1, 2]", 400, b"JSON object"),
                              (json.dumps(SCENE).encode(), 400, b"pixel: required"),
                              (json.dumps(dict(SCENE, pixel=[-1, 0])).encode(), 400, b"pixel: must be [x, y]"),
                              (json.dumps(dict(SCENE, pixel=[0, 160])).encode(), 400, b"outside the 200 x 160 image"),
                              (json.dumps(dict(SCENE, pixel=[0, 0], render={"s_k": -1})).encode(), 400, b"render.s_k"),
                              (json.dumps(dict(SCENE, pixel=[0, 0], pick="front")).encode(), 400, b"pick: must be"),
                              (json.dumps(dict(SCENE, pixel=[0, 0], volume="nope")).encode(), 404, b"nope")):
        status, _, answer = http(SERVER, "/api/probe", "POST", body)
        assert status == code and words in answer, (body[:60], status, answer)
        assert json.loads(answer)["error"], answer


def test_probes_answer_after_both_filters_have_drawn():
    """Once a volume has been drawn with both filters (both macrocell grids exist), probes still
    read its voxels: on GL (texture) and on the CPU backend, for an integer volume, a float one
    read where it lies and a float one far from 0 that the CPU backend copies to TF coordinates."""
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([PEAKCAST, "make-volume", "blobs", "--dims", "40", "36", "32", "--type", "float32",
                        "-o", f"{tmp}/plain.nrrd"], check=True, capture_output=True)
        n = 40 * 36 * 32
        far = [1.0e4 + 0.5 + 0.5 * math.sin(i * 0.01) for i in range(n)]
        pathlib.Path(tmp, "far.raw").write_bytes(struct.pack(f"<{n}f", *far))
        pathlib.Path(tmp, "far.raw.json").write_text(json.dumps({"dims": [40, 36, 32], "dtype": "float32"}))
        for backend in ("cpu", "gl"):
            with Server("--data", tmp, "--backend", backend) as s:
                for volume in ("plain.nrrd", "far.raw", "heptane_151"):
                    load = {"volume": volume, "image": {"width": 8, "height": 8}}  # loads it, with the default TF
                    assert http(s, "/api/render", "POST", json.dumps(load).encode())[0] == 200, volume
                    status, _, body = http(s, f"/api/volumes/{volume}")
                    info = json.loads(body)
                    assert status == 200, (volume, body)
                    lo, hi = info["range"]
                    scene = {"volume": volume, "image": {"width": 64, "height": 48},
                             "tf": {"points": [[lo, 1, 1, 1, 0.0], [hi, 1, 1, 1, 1.0]]}}
                    ask = lambda: http(s, "/api/probe", "POST", json.dumps(dict(scene, pixel=[32, 24])).encode())
                    status, _, first = ask()
                    assert status == 200 and json.loads(first)["hit"], (backend, volume, status, first)
                    for flt in ("tricubic", "trilinear"):
                        still = dict(scene, render={"filter": flt})
                        assert http(s, "/api/render", "POST", json.dumps(still).encode())[0] == 200, (backend, volume, flt)
                    status, _, again = ask()
                    assert status == 200 and json.loads(again) == json.loads(first), (backend, volume, status, again)
            print(f"  {backend}: probes of 3 volumes answer alike before and after both filters drew them")


def test_data_directory_listing():
    """GET /api/files: one folder of the data directories at a time, names relative to them."""
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        (root / "cells.nrrd").write_bytes(b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n\n" + bytes(8))
        (root / "beads.raw").write_bytes(bytes(8))
        (root / "beads.raw.json").write_text(json.dumps({"dims": [2, 2, 2], "dtype": "uint8"}))
        (root / "orphan.raw").write_bytes(bytes(8))       # no sidecar: a header's data, not a volume
        (root / ".hidden.nrrd").write_bytes(b"")
        (root / "notes.txt").write_text("not a volume")
        (root / "slices").mkdir()
        for i in range(2):
            (root / "slices" / f"z{i}.tif").write_bytes(b"")
        (root / "two").mkdir()
        for n in ("a.nhdr", "b.mhd"):
            (root / "two" / n).write_text("")
        (root / "outside").symlink_to("/etc")              # a link out is not offered
        with Server("--data", tmp) as s:
            def files(dir_=None):
                status, _, body = http(s, "/api/files" + (f"?dir={dir_}" if dir_ is not None else ""))
                return status, json.loads(body)
            status, top = files()
            assert status == 200 and top["dir"] == "" and not top["truncated"], top
            kinds = {e["name"]: e["kind"] for e in top["entries"]}
            # Both data directories, merged: the test data and this one.
            assert kinds["cells.nrrd"] == "volume" and kinds["beads.raw"] == "volume", kinds
            assert kinds["heptane_151.nrrd"] == "volume" and kinds["headsq"] == "stack", kinds
            assert kinds["slices"] == "stack" and kinds["two"] == "folder", kinds
            for absent in ("orphan.raw", ".hidden.nrrd", "notes.txt", "outside", "beads.raw.json"):
                assert absent not in kinds, (absent, kinds)
            folders = [e["kind"] != "volume" for e in top["entries"]]
            assert folders == sorted(folders, reverse=True), "folders first"
            assert tmp not in json.dumps(top) and str(DATA) not in json.dumps(top), "no server path"
            status, two = files("two")
            assert [e["path"] for e in two["entries"]] == ["two/a.nhdr", "two/b.mhd"], two
            # What is listed opens by its path.
            status, _, body = http(s, "/api/render", "POST", json.dumps(
                {"volume": "cells.nrrd", "image": {"width": 8, "height": 8}}).encode())
            assert status == 200, body[:200]
            for bad, words in (("..", "outside"), ("/etc", "relative"), ("nope", "no such"),
                               ("outside", "outside"), ("cells.nrrd", "not a folder")):
                status, body = files(bad)
                assert status == 404 and words in body["message"] and tmp not in body["message"], (bad, body)


def test_slices_are_the_voxels_seen_from_the_axis_side():
    """POST /api/slice against the voxels `peakcast convert` writes: with the window 0..255 a
    uint8 volume's grey is its value; a z slice seen from +z with +y up, an x slice from +x."""
    import numpy as np
    with tempfile.TemporaryDirectory() as tmp:
        raw = pathlib.Path(tmp) / "h.raw"
        subprocess.run([PEAKCAST, "convert", str(DATA / "heptane_151.nrrd"), str(raw)], check=True, capture_output=True)
        meta = json.loads(raw.with_name("h.raw.json").read_text())
        nx, ny, nz = meta["dims"]
        vox = np.fromfile(raw, dtype=np.uint8).reshape(nz, ny, nx)
    for sl, expect in (({"axis": "z", "index": 70}, vox[70, ::-1, :]), ({"axis": "x", "index": 80}, vox[::-1, ::-1, 80].T)):
        body = {"volume": "heptane_151", "slice": dict(sl, window=[0, 255])}
        status, headers, png = http(SERVER, "/api/slice", "POST", json.dumps(body).encode())
        assert status == 200 and headers["Content-Type"] == "image/png", (status, png[:200])
        img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))[:, :, 0]
        assert img.shape == expect.shape and (int(headers["X-Width"]), int(headers["X-Height"])) == img.shape[::-1]
        assert np.array_equal(img, expect), f"{sl}: {np.abs(img.astype(int) - expect).max()} off"
        assert headers["X-TF-Source"] == "window" and headers["X-Index"] == str(sl["index"])
    # With an image: fitted into it; with the TF's colours (the automatic TF).
    body = {"volume": "heptane_151", "image": {"width": 64, "height": 32}, "slice": {"axis": "y", "index": 10}}
    status, headers, png = http(SERVER, "/api/slice", "POST", json.dumps(body).encode())
    assert status == 200 and Image.open(io.BytesIO(png)).size == (64, 32) and headers["X-TF-Source"] == "auto"
    assert http(SERVER, "/api/slice")[0] == 405
    for sl, code, words in (({"axis": "z", "index": nz}, 400, b"outside 0..%d" % (nz - 1)),
                            ({"axis": "q", "index": 1}, 400, b"slice.axis"),
                            ({"plane": {"point": [0, 0, 0], "normal": [0, 0, 0]}}, 400, b"must not be zero"),
                            (None, 400, b"slice")):
        body = {"volume": "heptane_151", **({"slice": sl} if sl else {})}
        status, _, answer = http(SERVER, "/api/slice", "POST", json.dumps(body).encode())
        assert status == code and words in answer, (sl, status, answer)
    status, _, answer = http(SERVER, "/api/slice", "POST", b'{"volume": "nope", "slice": {"axis": "x", "index": 0}}')
    assert status == 404, answer


if __name__ == "__main__":
    with Server("--max-sessions", "20") as s:
        SERVER = s
        run_tests([test_health_and_volumes, test_rest_render_equals_cli_render, test_rest_jpeg_and_refusals,
                   test_rest_stills_honour_the_clip,
                   test_sixteen_sessions_share_one_gpu_copy, test_metrics_parse_as_prometheus_text,
                   test_static_client_is_served, test_probe_over_rest_and_websocket, test_probe_refusals,
                   test_probes_answer_after_both_filters_have_drawn, test_data_directory_listing,
                   test_slices_are_the_voxels_seen_from_the_axis_side])
