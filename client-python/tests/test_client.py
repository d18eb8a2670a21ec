"""The Python client against a live server: an uploaded array renders pixel for pixel like
`peakcast render` of the same data written to a file, in any memory order; every refusal answers
by name and leaves no file and no volume; a disconnect or a stall mid-upload leaves nothing; the
examples run; the package installs with pip."""
import json
import os
import pathlib
import socket
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest

from conftest import DATA, PEAKCAST, ROOT, blobs, no_uploads_left
import peakcast


SCENE = {"image": {"width": 96, "height": 80},
         "camera": {"eye": [60, 50, 70], "center": [13.5, 11.5, 14.25], "up": [0, 1, 0]},
         "render": {"classification": "peaks", "shading": True}}


def cli_render(array, spacing, scene):
    """`peakcast render` of the same voxels written as raw + JSON sidecar."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        np.ascontiguousarray(array).astype(array.dtype.newbyteorder("<")).tofile(tmp / "v.raw")
        (tmp / "v.json").write_text(json.dumps({"dims": list(array.shape[::-1]), "dtype": str(array.dtype),
                                                "spacing": list(spacing), "data_file": "v.raw"}))
        (tmp / "s.json").write_text(json.dumps(dict(scene, volume="v.json")))
        subprocess.run([PEAKCAST, "render", tmp / "s.json", "-o", tmp / "s.png"], check=True, capture_output=True)
        from PIL import Image
        return np.asarray(Image.open(tmp / "s.png").convert("RGB"))


@pytest.mark.parametrize("dtype", [np.uint8, np.int8, np.uint16, np.int16, np.float32])
def test_an_uploaded_array_renders_like_peakcast_render(server, dtype):
    c = peakcast.Client(server.url)
    a = blobs(dtype=dtype)
    spacing = (1.0, 1.0, 1.5)
    vid = c.upload(a, spacing=spacing, name=f"blobs {np.dtype(dtype).name}")
    try:
        info = next(v for v in c.volumes() if v["id"] == vid)
        assert info["uploaded"] and info["dims"] == [28, 24, 20] and info["dtype"] == np.dtype(dtype).name, info
        assert info["spacing"] == list(spacing)
        assert info["units"] == "units", "an array sent without units: the server shows lengths in units"
        got = c.render(dict(SCENE, volume=vid))
        assert got.shape == (80, 96, 3) and got.dtype == np.uint8
        want = cli_render(a, spacing, SCENE)
        assert np.array_equal(got, want), f"{np.abs(got.astype(int) - want).max()} levels off"
        assert got.std() > 5, "the picture shows nothing"
    finally:
        c.delete(vid)


def test_units_travel_with_an_upload(server):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs(), spacing=(0.2, 0.2, 1.0), units="micrometer")
    try:
        assert c.volume(vid)["units"] == "µm"
    finally:
        c.delete(vid)
    with pytest.raises(peakcast.ServerError) as e:
        c.upload(blobs(), units="second")
    assert e.value.status == 400 and "units: 'second' is not a unit of length" in str(e.value), str(e.value)
    with pytest.raises(ValueError):
        c.upload(blobs(), units=3)


def test_a_time_series_uploads_and_renders_each_time_point(server):
    c = peakcast.Client(server.url)
    series = np.stack([blobs(seed=s) for s in (3, 4, 5)])  # [t, z, y, x]
    vid = c.upload(series, spacing=(1, 1, 1.5), units="um", name="series")
    single = c.upload(series[2], spacing=(1, 1, 1.5), units="um", name="t2")
    try:
        info = c.volume(vid)
        assert info["times"] == 3 and info["time"] == 0 and info["dims"] == [28, 24, 20], info
        t2 = c.render(dict(SCENE, volume=vid, time=2))
        assert np.array_equal(t2, c.render(dict(SCENE, volume=single))), "time point 2 is the third volume sent"
        assert not np.array_equal(t2, c.render(dict(SCENE, volume=vid, time=0)))
        with pytest.raises(peakcast.ServerError) as e:
            c.render(dict(SCENE, volume=vid, time=3))
        assert e.value.status == 400 and "time: time point 3 is outside the volume's 0..2" in e.value.message
    finally:
        c.delete(vid)
        c.delete(single)
    with pytest.raises(ValueError, match="does not draw channels yet"):
        c.upload(series, axes="czyx")
    with pytest.raises(ValueError, match=r"\[t, z, y, x\]"):
        c.upload(np.zeros((2, 2, 4, 4, 4), np.uint8))
    status, answer = raw_post(server, "dims=28,24,20&dtype=uint16&times=2", series.tobytes())
    assert status == 400 and "need 53760 bytes" in answer["message"], answer  # 2 time points, 3 sent
    status, answer = raw_post(server, "dims=28,24,20&dtype=uint16&times=0", series[0].tobytes())
    assert status == 400 and "times must be an integer" in answer["message"], answer


def test_memory_order_does_not_change_the_picture(server):
    c = peakcast.Client(server.url)
    a = blobs()
    images = []
    for variant in (np.ascontiguousarray(a), np.asfortranarray(a), a[::-1][::-1], a.byteswap().view(a.dtype.newbyteorder())):
        vid = c.upload(variant, spacing=(1, 1, 1.5))
        try:
            images.append(c.render(dict(SCENE, volume=vid)))
        finally:
            c.delete(vid)
    for img in images[1:]:
        assert np.array_equal(img, images[0])


def test_a_file_uploads_as_itself(server, tmp_path):
    c = peakcast.Client(server.url)
    vid = c.upload(DATA / "heptane_151.nrrd")
    try:
        info = c.volume(vid)
        assert info["name"] == "heptane_151.nrrd" and info["dims"] == [151, 151, 151]
        c.render_png({"volume": vid, "image": {"width": 64, "height": 64}}, tmp_path / "h.png")
        assert (tmp_path / "h.png").read_bytes()[:4] == b"\x89PNG"
    finally:
        c.delete(vid)


def raw_post(server, query, body, headers=None, token=None):
    """A POST /api/volumes as any HTTP client sends it (no Expect), for refusals the client
    itself would not let through."""
    import http.client
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=30)
    h = dict(headers or {})
    if token:
        h["Authorization"] = "Bearer " + token
    conn.request("POST", "/api/volumes?" + query, body=body, headers=h)
    r = conn.getresponse()
    out = r.status, json.loads(r.read() or b"{}")
    conn.close()
    return out


def test_refusals_answer_by_name_and_leave_nothing(server):
    c = peakcast.Client(server.url)
    before, volumes = server.files(), c.volumes()
    cases = [
        # (what, query, body, status, code)
        # A raw body must hold exactly what its dims and dtype need (both sizes named).
        ("truncated", "dims=28,24,21&dtype=uint16", blobs().tobytes(), 400, "bad_upload"),
        ("extra bytes", "dims=28,24,19&dtype=uint16", blobs().tobytes(), 400, "bad_upload"),
        ("truncated nrrd", "", b"NRRD0004\ntype: uint16\ndimension: 3\nsizes: 28 24 21\nencoding: raw\n\n" + blobs().tobytes(),
         422, "bad_volume"),
        ("wrong dims", "dims=28,24,0&dtype=uint16", blobs().tobytes(), 400, "bad_upload"),
        ("wrong dims count", "dims=28,24&dtype=uint16", blobs().tobytes(), 400, "bad_upload"),
        ("bad dtype", "dims=28,24,20&dtype=uint32", blobs().tobytes(), 400, "bad_upload"),
        ("bad spacing", "dims=28,24,20&dtype=uint16&spacing=1,0,1", blobs().tobytes(), 400, "bad_upload"),
        ("no header", "name=x", b"\x01\x02" * 1000, 415, "unsupported_upload"),
        ("detached nrrd", "", (DATA / "nucleon.nhdr").read_bytes(), 415, "unsupported_upload"),
        ("empty", "dims=2,2,2&dtype=uint8", b"", 400, "bad_upload"),
        # More voxels than the server's limit (2^32): refused from the header, before any allocation.
        ("voxel limit", "", b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4096 4096 512\nencoding: raw\n\n" + b"\0" * 4096,
         422, "bad_volume"),
    ]
    for what, query, body, status, code in cases:
        print("case", what)
        got_status, answer = raw_post(server, query, body)
        assert (got_status, answer.get("error")) == (status, code), (what, got_status, answer)
        assert str(server.upload_dir) not in answer.get("message", ""), (what, answer)  # no server path
        no_uploads_left(server, before)
    # Through the client: too large (4 MiB per upload here) is refused before the body is sent.
    with pytest.raises(peakcast.ServerError) as e:
        c.upload(np.zeros((80, 128, 128), np.uint8))  # 1.25 MiB: fine
        c.upload(np.zeros((160, 128, 256), np.uint8))  # 5 MiB: too large
    assert e.value.status == 413 and e.value.code == "too_large"
    for v in c.volumes():
        if v["id"] not in [w["id"] for w in volumes]:
            c.delete(v["id"])
    no_uploads_left(server, before)
    assert c.volumes() == volumes
    with pytest.raises(ValueError):
        c.upload(np.zeros((4, 4, 4), np.int64))
    with pytest.raises(peakcast.ServerError) as e:
        c.delete("heptane_151_nope")
    assert e.value.status == 404


def test_the_budget_fills(server):
    c = peakcast.Client(server.url)
    before = server.files()
    kept = [c.upload(np.full((64, 128, 128), i, np.uint16) + np.arange(128, dtype=np.uint16)) for i in range(2)]  # 2 MiB each
    try:
        kept.append(c.upload(np.zeros((64, 128, 128), np.uint16) + 7))  # 6 of 10 MiB
        kept.append(c.upload(np.zeros((64, 128, 128), np.uint16) + 9))  # 8 of 10 MiB
        with pytest.raises(peakcast.ServerError) as e:
            c.upload(np.zeros((96, 128, 128), np.uint16) + 5)  # 3 MiB: past the budget
        assert e.value.status == 507 and e.value.code == "upload_budget", e.value
    finally:
        for vid in kept:
            c.delete(vid)
    no_uploads_left(server, before)


def test_no_token_is_refused(guarded):
    before = guarded.files()
    status, answer = raw_post(guarded, "dims=28,24,20&dtype=uint16", blobs().tobytes())
    assert (status, answer["error"]) == (401, "unauthorized")
    with pytest.raises(peakcast.ServerError) as e:
        peakcast.Client(guarded.url).upload(blobs())
    assert e.value.status == 401
    vid = peakcast.Client(guarded.url, token="sesame").upload(blobs())
    peakcast.Client(guarded.url, token="sesame").delete(vid)
    no_uploads_left(guarded, before)


def test_a_client_past_its_rate_is_refused(guarded):
    c = peakcast.Client(guarded.url, token="sesame", retries=0)
    before = guarded.files()
    refused = None
    for i in range(14):  # a burst of 10, then 1 a second
        try:
            c.delete(c.upload(blobs(shape=(4, 4, 4), dtype=np.uint8)))
        except peakcast.ServerError as e:
            refused = e
            break
    assert refused is not None and refused.status == 429 and refused.code == "rate_limited", refused
    no_uploads_left(guarded, before)


def start_stalled_upload(server, size=1 << 20):
    """An upload that sends its header and a little of its body, then nothing."""
    s = socket.create_connection(("127.0.0.1", server.port))
    s.sendall(f"POST /api/volumes?dims=64,64,256&dtype=uint8 HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: {size}\r\n\r\n"
              .encode() + b"\0" * 1000)
    return s


def test_concurrent_limit_stall_and_disconnect_leave_nothing(server):
    c = peakcast.Client(server.url, retries=0)
    before = server.files()
    stalled = start_stalled_upload(server)
    time.sleep(0.3)
    assert any(f.startswith(".incoming/") for f in server.files()), "the upload is not being received"
    # One at a time here (--max-uploads 1): the next is refused by name.
    with pytest.raises(peakcast.ServerError) as e:
        c.upload(blobs())
    assert e.value.status == 503 and e.value.code == "uploads_busy"
    # The stall ends after --upload-timeout (2 s): the connection closes, the file goes.
    stalled.settimeout(10)
    t0 = time.time()
    assert stalled.recv(1000) == b"", "the stalled upload got an answer instead of being closed"
    assert time.time() - t0 < 8
    stalled.close()
    time.sleep(0.3)
    no_uploads_left(server, before)
    # A client that goes away mid-upload leaves nothing either.
    gone = start_stalled_upload(server)
    time.sleep(0.3)
    gone.close()
    time.sleep(0.5)
    no_uploads_left(server, before)
    vid = c.upload(blobs())  # and the slot is free again
    c.delete(vid)


@pytest.mark.parametrize("example", ["orbit.py", "tf_sweep.py", "isosurface.py"])
def test_examples_run(server, tmp_path, example):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs(), spacing=(1, 1, 1.5), name="example")
    args = {"orbit.py": ["--volume", vid, "--frames", "3", "--size", "64", "--out", str(tmp_path / "o")],
            "tf_sweep.py": ["--volume", vid, "--steps", "3", "--size", "64", "--out", str(tmp_path / "s")],
            "isosurface.py": ["--n", "32", "--out", str(tmp_path / "iso.png")]}[example]
    env = dict(os.environ, PYTHONPATH=str(ROOT / "client-python"))
    try:
        r = subprocess.run([sys.executable, str(ROOT / "client-python/examples" / example), "--url", server.url, *args],
                           capture_output=True, text=True, env=env, timeout=300)
        assert r.returncode == 0, r.stderr
        pngs = list(tmp_path.rglob("*.png"))
        assert len(pngs) == {"orbit.py": 3, "tf_sweep.py": 3, "isosurface.py": 1}[example], pngs
        assert all(p.read_bytes()[:4] == b"\x89PNG" for p in pngs)
    finally:
        c.delete(vid)


def test_pip_installs_the_package(tmp_path):
    """The install commands of client-python/README.md, as written (the venv's folder swapped for a
    temporary one, the checkout for a copy): offline, on Debian 12's externally managed Python."""
    import re
    import shutil
    src = tmp_path / "client-python"
    # A copy: pip builds in the source folder (build/, *.egg-info), which is not the checkout's.
    shutil.copytree(ROOT / "client-python", src, ignore=shutil.ignore_patterns("tests", "build", "*.egg-info", "__pycache__"))
    readme = (ROOT / "client-python/README.md").read_text()
    block = next(b for b in re.findall(r"```sh\n(.*?)```", readme, re.S) if "pip install" in b)
    venv = tmp_path / "venv"
    for line in block.strip().splitlines():
        line = line.replace("~/peakcast-venv", str(venv)).replace("./client-python", str(src))
        line = re.sub(r"^python3 ", sys.executable + " ", line)  # Debian's python3: the one running the tests
        env = {k: v for k, v in os.environ.items() if not k.startswith(("PIP_", "VIRTUAL_ENV"))}
        env["PIP_NO_INDEX"] = "1"  # no index is reachable here: the line must not need one
        r = subprocess.run(line, shell=True, capture_output=True, text=True, cwd=tmp_path, env=env)
        assert r.returncode == 0, (line, r.stderr)
    r = subprocess.run([str(venv / "bin/python"), "-c", "import peakcast, sys; print(peakcast.__file__)"],
                       capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 0 and str(venv) in r.stdout, (r.stdout, r.stderr)
