#!/usr/bin/env python3
"""POST /api/movie on the running server: a png-zip orbit's frames are, byte for byte, the stills
of the same cameras (worked out here, apart from the server's arithmetic); key frames reach each
key's camera and TF and blend between; the file streams (its first frames arrive before the last
is drawn); mp4 and webm are the containers they say; each refusal is a clear error before any
work; a client that hangs up mid-movie ends it and the server serves on."""
import io, json, math, pathlib, socket, sys, time, zipfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

SCENE = {"volume": "heptane_151", "image": {"width": 96, "height": 64},
         "render": {"classification": "post", "step": 1.0},
         "tf": {"points": [[0, 0, 0, 0, 0], [0.3, 0.9, 0.5, 0.2, 0.05], [1, 1, 1, 1, 0.8]]}}
CAMERA = {"eye": [75, 90, 420], "center": [75, 75, 75], "up": [0, 1, 0]}
JSON = {"Content-Type": "application/json"}


def post_movie(body, path="/api/movie"):
    return http(SERVER, path, "POST", json.dumps(body).encode(), JSON)


def still(scene):
    status, _, png = http(SERVER, "/api/render?format=png", "POST", json.dumps(scene).encode(), JSON)
    assert status == 200, png[:300]
    return np.asarray(decode_image(png))


def frames_of(zip_bytes):
    z = zipfile.ZipFile(io.BytesIO(zip_bytes))
    assert z.testzip() is None, "a CRC does not match"
    return [np.asarray(decode_image(z.read(n))) for n in sorted(z.namelist())], z.namelist()


def turned(v, axis, deg):
    """v turned right-handed about the unit axis (Rodrigues), in plain Python."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    v, t = np.asarray(v, float), math.radians(deg)
    return v * math.cos(t) + np.cross(a, v) * math.sin(t) + a * np.dot(a, v) * (1 - math.cos(t))


def test_an_orbit_is_the_stills_of_its_cameras():
    body = dict(SCENE, camera=CAMERA, path={"orbit": {"axis": [0, 1, 0], "degrees": 360}}, frames=6, fps=12,
                format="png-zip")
    status, headers, data = post_movie(body)
    assert status == 200, data[:300]
    assert headers["Content-Type"] == "application/zip" and headers["X-Frames"] == "6", headers
    assert headers.get("Transfer-Encoding") == "chunked", "the movie is streamed, not sized up front"
    assert "heptane_151.zip" in headers["Content-Disposition"]
    frames, names = frames_of(data)
    assert names == [f"frame_{i:05d}.png" for i in range(6)], names
    center = np.array(CAMERA["center"], float)
    for i, frame in enumerate(frames):  # 360 / 6: 0, 60, ..., 300 (a loop: no frame repeats the first)
        eye = center + turned(np.array(CAMERA["eye"]) - center, [0, 1, 0], 60 * i)
        cam = dict(CAMERA, eye=eye.tolist())
        expect = still(dict(SCENE, camera=cam))
        diff = np.abs(frame.astype(int) - expect.astype(int)).max()
        assert diff <= 1, f"frame {i} differs from the still of its camera by {diff}"
    assert np.abs(frames[0].astype(int) - frames[3].astype(int)).mean() > 1, "the camera did not move"


def test_keys_reach_each_key_and_blend_between():
    red = {"points": [[0, 1, 0, 0, 0], [1, 1, 0, 0, 0.9]]}
    blue = {"points": [[0, 0, 0, 1, 0], [1, 0, 0, 1, 0.9]]}
    front, side = dict(CAMERA, eye=[75, 75, 420]), dict(CAMERA, eye=[420, 75, 75])
    body = dict(SCENE, path={"keys": [{"camera": front, "tf": red}, {"camera": side, "tf": blue}]}, frames=3,
                format="png-zip")
    status, _, data = post_movie(body)
    assert status == 200, data[:300]
    frames, _ = frames_of(data)
    assert np.abs(frames[0].astype(int) - still(dict(SCENE, camera=front, tf=red)).astype(int)).max() <= 1
    assert np.abs(frames[2].astype(int) - still(dict(SCENE, camera=side, tf=blue)).astype(int)).max() <= 1
    # Halfway: the TF's colour half red, half blue (the same opacity), the eye at 45 degrees.
    mid_eye = np.array(CAMERA["center"]) + turned(np.array(front["eye"]) - CAMERA["center"], [0, 1, 0], 45)
    assert abs(np.linalg.norm(mid_eye - CAMERA["center"]) - 345) < 1e-6
    half = {"points": [[0, 0.5, 0, 0.5, 0], [1, 0.5, 0, 0.5, 0.9]]}
    expect = still(dict(SCENE, camera=dict(CAMERA, eye=mid_eye.tolist()), tf=half))
    diff = np.abs(frames[1].astype(int) - expect.astype(int)).max()
    assert diff <= 1, f"the middle frame differs from the blended still by {diff}"


def test_the_movie_streams_while_it_is_made():
    # 16 frames that each take a while (under a sanitizer, seconds): the first must come long
    # before the last.
    body = dict(SCENE, camera=CAMERA, path={"orbit": {"degrees": 90}}, frames=16, format="png-zip",
                image={"width": 160, "height": 160}, render={"classification": "post", "step": 0.5})
    s = socket.create_connection((SERVER.host, SERVER.port), timeout=120)
    raw = json.dumps(body).encode()
    s.sendall(b"POST /api/movie HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
              b"Content-Length: " + str(len(raw)).encode() + b"\r\n\r\n" + raw)
    start, first, got = time.time(), None, b""
    while True:
        piece = s.recv(1 << 16)
        if not piece:
            break
        got += piece
        if first is None and got.count(b"PK\x03\x04") >= 1:
            first = time.time() - start
        if got.endswith(b"0\r\n\r\n"):
            break
    total = time.time() - start
    s.close()
    assert got.startswith(b"HTTP/1.1 200"), got[:200]
    assert first is not None and first < total / 2, f"the first frame came at {first:.2f} s of {total:.2f} s"


def test_video_containers_are_what_they_say():
    for fmt, kind, magic in (("mp4", "video/mp4", b"ftyp"), ("webm", "video/webm", b"\x1a\x45\xdf\xa3")):
        body = dict(SCENE, camera=CAMERA, path={"orbit": {"degrees": 30}}, frames=8, format=fmt)
        status, headers, data = post_movie(body)
        assert status == 200, data[:300]
        assert headers["Content-Type"] == kind and headers["X-Format"] == fmt, headers
        assert magic in data[:16], f"{fmt}: starts {data[:16]!r}"
        if fmt == "mp4":  # fragmented: an empty moov first, then moof + mdat (playable while it streams)
            assert data.find(b"moov") < data.find(b"moof") < data.find(b"mdat"), "not a fragmented MP4"
            assert headers["X-Encoder"] == "libx264"


def test_refusals_are_clear_and_cost_nothing():
    cases = [
        (dict(SCENE, frames=0), 400, "frames: must be in [1, 3600]"),
        (dict(SCENE, format="gif"), 400, "format: 'gif' is not one of mp4, webm, png-zip"),
        (dict(SCENE, path={"spiral": {}}), 400, "path: must be"),
        (dict(SCENE, path={"keys": [{"zoom": 2}]}), 400, "path.keys[0].zoom: unknown key"),
        (dict(SCENE, path={"keys": [{}, {}, {}]}, frames=2), 400, "3 keys need at least as many frames"),
        (dict(SCENE, image={"width": 95, "height": 64}, format="mp4"), 400, "even width and height"),
        (dict(SCENE, path={"keys": [{"time": 0}, {"time": 4}]}), 400, "time"),
        (dict(SCENE, volume="no_such_volume"), 404, ""),
        (dict(SCENE, path={"keys": [{"camera": CAMERA}, {"camera": dict(CAMERA, projection="orthographic",
                                                                      height=100)}]}), 400, "one projection"),
        (dict(SCENE, image={"width": 4096, "height": 4096}, render={"step": 0.01}), 422, "max_still_samples"),
        (dict(SCENE, image={"width": 2048, "height": 2048}, frames=400, format="png-zip"), 422, "stays under 4 GB"),
    ]
    for body, code, words in cases:
        status, _, answer = post_movie(body)
        assert status == code, (body, status, answer[:300])
        assert words in json.loads(answer)["message"], (words, answer[:300])
    status, _, answer = http(SERVER, "/api/movie")
    assert status == 405, answer[:200]
    status, _, answer = http(SERVER, "/api/movie", "POST", b"{not json", JSON)
    assert status == 400 and b"not valid JSON" in answer
    status, _, answer = http(SERVER, "/api/health")
    assert status == 200 and json.loads(answer)["stills_queued"] == 0, "a refusal left work queued"


def test_a_client_that_hangs_up_ends_the_movie():
    body = dict(SCENE, camera=CAMERA, frames=400, format="png-zip", image={"width": 256, "height": 256},
                render={"classification": "post", "step": 0.25})
    raw = json.dumps(body).encode()
    s = socket.create_connection((SERVER.host, SERVER.port), timeout=60)
    s.sendall(b"POST /api/movie HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: application/json\r\n"
              b"Content-Length: " + str(len(raw)).encode() + b"\r\n\r\n" + raw)
    got = b""
    while got.count(b"PK\x03\x04") < 2:
        got += s.recv(1 << 16)
    s.close()
    deadline = time.time() + 60
    while time.time() < deadline:
        _, _, metrics = http(SERVER, "/metrics")
        if b'peakcast_movies_total{outcome="cancelled"}' in metrics:
            break
        time.sleep(0.2)
    else:
        raise AssertionError("the movie went on after its client left")
    while time.time() < deadline:  # its frame in flight stops at its next band
        status, _, answer = http(SERVER, "/api/health")
        if status == 200 and json.loads(answer)["stills_queued"] == 0:
            break
        time.sleep(0.2)
    else:
        raise AssertionError("the movie's stills stayed queued after its client left")
    assert still(dict(SCENE, camera=CAMERA)).shape == (64, 96, 3), "the server serves on"


def test_a_full_still_queue_makes_frames_wait_not_fail():
    global SERVER
    main, body = SERVER, dict(SCENE, camera=CAMERA, path={"orbit": {"degrees": 60}}, frames=6, format="png-zip")
    with Server("--max-queued-stills", "1") as SERVER:  # the movie's second frame finds the queue full
        try:
            status, _, data = post_movie(body)
            assert status == 200, data[:300]
            assert len(frames_of(data)[0]) == 6
        finally:
            SERVER = main


if __name__ == "__main__":
    with Server() as SERVER:
        run_tests([test_an_orbit_is_the_stills_of_its_cameras, test_keys_reach_each_key_and_blend_between,
                   test_the_movie_streams_while_it_is_made, test_video_containers_are_what_they_say,
                   test_refusals_are_clear_and_cost_nothing, test_a_client_that_hangs_up_ends_the_movie,
                   test_a_full_still_queue_makes_frames_wait_not_fail])
