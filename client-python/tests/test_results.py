"""What the server says reaches the script: a still keeps its warnings, TF source, level and
timings; refusals that say when to come back are waited out (and can be raised at once); one
connection serves a thread's calls; numpy values go into scenes; values and arguments that would
be lost or ignored are refused before anything is sent."""
import threading
import time

import numpy as np
import pytest

from conftest import DATA, Server, blobs, no_uploads_left
import peakcast

SMALL = {"image": {"width": 48, "height": 40}}


def test_a_still_keeps_what_the_server_said(server, tmp_path):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    try:
        auto = c.render(dict(SMALL, volume=vid))
        assert isinstance(auto, peakcast.Image) and isinstance(auto, np.ndarray) and auto.shape == (40, 48, 3)
        assert auto.tf_source == "auto" and auto.warnings == [] and auto.level == 0 and auto.time == 0, auto.info
        assert auto.info.render_ms > 0 and auto.info.variant, auto.info
        assert auto[10:20].tf_source == "auto" and type(np.asarray(auto)) is np.ndarray  # views keep it
        # Peaks with a TF that has no opacity peak: the server's warning, word for word.
        ramp = {"points": [[0, 1, 1, 1, 0], [65535, 1, 1, 1, 1]]}
        flat = c.render(dict(SMALL, volume=vid, tf=ramp, render={"classification": "peaks"}))
        assert flat.tf_source == "scene" and len(flat.warnings) == 1, flat.info
        assert "no opacity peak" in flat.warnings[0], flat.warnings
        info = c.render_png(dict(SMALL, volume=vid, tf=ramp, render={"classification": "peaks"}), tmp_path / "p.png")
        assert info.warnings == flat.warnings
    finally:
        c.delete(vid)


def test_numpy_numbers_and_arrays_go_into_a_scene(server):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    try:
        plain = c.render({"volume": vid, "image": {"width": 48, "height": 40},
                          "tf": {"points": [[0, 1, 0.5, 0, 0], [40000, 1, 1, 1, 0.4], [65535, 1, 1, 1, 0]]}})
        points = np.array([[0, 1, 0.5, 0, 0], [40000, 1, 1, 1, 0.4], [65535, 1, 1, 1, 0]])
        numpy = c.render({"volume": vid, "image": {"width": np.int64(48), "height": np.uint16(40)},
                          "tf": {"points": points}})
        assert np.array_equal(plain, numpy)
        with pytest.raises(ValueError, match="NaN or infinity"):
            c.render({"volume": vid, "image": {"width": 48, "height": 40}, "render": {"step": np.float64("nan")}})
        with pytest.raises(TypeError, match="not set"):
            c.render({"volume": vid, "image": {"width": 48, "height": 40}, "render": {"step": {1}}})
    finally:
        c.delete(vid)


def test_values_that_would_be_lost_are_refused_before_sending(server, tmp_path):
    c = peakcast.Client(server.url)
    before = server.files()
    with pytest.raises(ValueError, match="do not fit in float32"):
        c.upload(np.full((4, 4, 4), 1e39))
    assert server.files() == before
    fine = blobs(dtype=np.float64) * 1e30  # fits: sent as float32, and kept
    vid = c.upload(fine)
    assert c.volume(vid)["range"][1] == pytest.approx(1e30, rel=1e-6)
    c.delete(vid)
    # A file's header gives its spacing: a spacing given beside it would be ignored.
    with pytest.raises(ValueError, match="spacing: a file's own header gives them"):
        c.upload(DATA / "heptane_151.nrrd", spacing=(5, 5, 5))
    with pytest.raises(ValueError, match="origin, units"):
        c.upload(DATA / "heptane_151.nrrd", origin=(0, 0, 0), units="mm")
    no_uploads_left(server, before)


def test_refusals_with_retry_after_are_waited_out(tmp_path):
    """Eight threads at once against a queue of two: without retries some are refused (503
    queue_full, Retry-After 5), with them every still arrives."""
    s = Server(tmp_path, "--max-queued-stills", "2")
    try:
        scene = {"volume": "heptane_151.nrrd", "image": {"width": 192, "height": 192},
                 "render": {"classification": "peaks", "shading": True, "step": 0.25}}

        def burst(client):
            out = [None] * 8

            def one(i):
                try:
                    out[i] = client.render(scene)
                except peakcast.ServerError as e:
                    out[i] = e
            threads = [threading.Thread(target=one, args=(i,)) for i in range(8)]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            return out

        refused = [r for r in burst(peakcast.Client(s.url, retries=0)) if isinstance(r, peakcast.ServerError)]
        assert refused and all((e.status, e.code, e.retry_after) == (503, "queue_full", 5) for e in refused), refused
        # Honouring Retry-After (5 s) as given: enough for a sanitizer build's seconds-long stills.
        t0 = time.time()
        waited = burst(peakcast.Client(s.url, retries=12, max_retry_wait=5))
        late = [r for r in waited if not isinstance(r, peakcast.Image)]
        assert not late, late
        print(f"  {len(refused)} of 8 refused without retries; all 8 with them in {time.time() - t0:.1f} s")
    finally:
        s.stop()


def test_a_rate_limit_says_when_the_next_upload_may_come(guarded):
    c = peakcast.Client(guarded.url, token="sesame", retries=0)
    before = guarded.files()
    refused = None
    for _ in range(14):
        try:
            c.delete(c.upload(blobs(shape=(4, 4, 4), dtype=np.uint8)))
        except peakcast.ServerError as e:
            refused = e
            break
    assert refused is not None and refused.status == 429, refused
    assert "burst of 10" in refused.message and "is spent" in refused.message, refused.message
    assert refused.retry_after == 1, refused.retry_after  # one upload a second comes back
    # With retries, the same burst goes through: each refusal waits its Retry-After.
    patient = peakcast.Client(guarded.url, token="sesame")
    for _ in range(4):
        patient.delete(patient.upload(blobs(shape=(4, 4, 4), dtype=np.uint8)))
    no_uploads_left(guarded, before)


def test_one_connection_serves_a_thread(server):
    with peakcast.Client(server.url) as c:
        c.health()
        first = c._http._kept().sock
        c.volumes()
        c.render(dict(SMALL, volume="heptane_151.nrrd"))
        assert c._http._kept().sock is first, "a new connection for each call"
        seen = []
        t = threading.Thread(target=lambda: (c.health(), seen.append(c._http._kept().sock)))
        t.start()
        t.join()
        assert seen[0] is not first  # each thread has its own
    assert first.fileno() == -1  # closed on leaving the with block
    assert c.health()["status"] == "ok"  # and a later call opens a new one


def test_a_deleted_upload_is_named_as_deleted(server):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    c.delete(vid)
    with pytest.raises(peakcast.ServerError) as e:
        c.render(dict(SMALL, volume=vid))
    assert e.value.status == 404 and "was deleted" in e.value.message, e.value
    assert "data directories" not in e.value.message, e.value


def test_a_volume_draws_the_same_at_any_scale_within_the_bounds(server):
    """The same voxels at spacing 1e-12, 1 and 1e12 (default camera, automatic TF) draw one
    picture; past the bounds the raw header is refused before any voxel is sent. Before, 1e-12
    drew the volume small (the default camera's distance had a floor) and 1e300 uploaded, then
    every render failed."""
    c = peakcast.Client(server.url)
    before = server.files()
    a = blobs()
    pictures = {}
    for s in (1e-12, 1.0, 1e12):
        vid = c.upload(a, spacing=(s, s, s))
        try:
            pictures[s] = np.asarray(c.render(dict(SMALL, volume=vid, render={"classification": "peaks",
                                                                              "shading": True}))).astype(int)
        finally:
            c.delete(vid)
    for s in (1e-12, 1e12):
        worst = np.abs(pictures[s] - pictures[1.0]).max()
        assert worst <= 1, (s, worst)
    for s in (1e-13, 1e13, 1e300):
        with pytest.raises(peakcast.ServerError) as e:
            c.upload(a, spacing=(1, s, 1))
        assert e.value.status == 400 and "outside 1e-12..1e+12" in e.value.message, e.value
        assert "on axis y" in e.value.message, e.value
    with pytest.raises(peakcast.ServerError) as e:
        c.upload(a, origin=(0, 0, -1e16))
    assert e.value.status == 400 and "origin" in e.value.message, e.value
    no_uploads_left(server, before)


def test_an_upload_past_the_memory_budget_is_refused_before_its_body(tmp_path):
    """The query's dims decide it: the answer comes to the headers alone (no 100 Continue), and the
    advice needs no shell on the server."""
    import socket
    s = Server(tmp_path, "--memory-budget-mib", "1")
    try:
        sock = socket.create_connection(("127.0.0.1", s.port), timeout=10)
        size = 128 * 128 * 64 * 2  # 2 MiB of uint16
        sock.sendall(f"POST /api/volumes?dims=128,128,64&dtype=uint16 HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                     f"Content-Length: {size}\r\nExpect: 100-continue\r\n\r\n".encode())
        answer = sock.recv(65536).decode("latin-1")
        sock.close()
        assert answer.startswith("HTTP/1.1 422") and "refused before the body was sent" in answer, answer[:400]
        assert "array[::2, ::2, ::2]" in answer, answer
        with pytest.raises(peakcast.ServerError) as e:  # the client hears it the same way
            peakcast.Client(s.url).upload(np.zeros((64, 128, 128), np.uint16))
        assert e.value.status == 422 and e.value.code == "bad_volume", e.value
        # A wrong length for the dims is refused before the body too.
        with pytest.raises(peakcast.ServerError) as e:
            peakcast.Client(s.url)._upload({"dims": "4,4,4", "dtype": "uint8"}, memoryview(b"\0" * 65), 65)
        assert e.value.status == 400 and "need 64 bytes; the body holds 65" in e.value.message, e.value
        vid = peakcast.Client(s.url).upload(np.zeros((16, 16, 16), np.uint16))  # within the budget: kept
        peakcast.Client(s.url).delete(vid)
    finally:
        s.stop()


def test_the_derived_tf_can_be_fetched_edited_and_sent_back(server):
    """POST /api/tf: the TF a scene without one is drawn with; sent back as the scene's TF it
    draws the same picture, and edited (opacity halved) it draws another."""
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    try:
        for classification in ("post", "peaks"):
            scene = dict(SMALL, volume=vid, render={"classification": classification})
            tf = c.tf(scene)
            assert c.last_tf_source == "auto" and len(tf["points"]) >= 2 and tf["opacity_unit"] == 1, tf
            auto = c.render(scene)
            same = c.render(dict(scene, tf=tf))
            assert same.tf_source == "scene" and np.abs(np.asarray(auto, int) - same).max() <= 1, classification
            assert c.tf(dict(scene, tf=tf)) == tf and c.last_tf_source == "scene"
        faint = dict(tf, points=[[v, r, g, b, a / 2] for v, r, g, b, a in tf["points"]])
        dimmer = c.render(dict(scene, tf=faint))
        change = np.abs(np.asarray(dimmer, int) - auto).mean()
        assert change > 1, change  # the edit is drawn
        with pytest.raises(peakcast.ServerError) as e:
            c.tf(dict(scene, volume="no-such.nrrd"))
        assert e.value.status == 404, e.value
    finally:
        c.delete(vid)


def test_the_readme_examples_run(server, tmp_path):
    """Every Python block of client-python/README.md, as written (the URL swapped in), each after a
    prelude that gives it a client, an array `volume` and an uploaded `vid`."""
    import re
    import os
    import subprocess
    import sys
    from conftest import ROOT
    readme = (ROOT / "client-python/README.md").read_text()
    blocks = re.findall(r"^```python\n(.*?)^```", readme, re.S | re.M)
    blocks += [re.sub(r"^  ", "", b, flags=re.M) for b in re.findall(r"^  ```python\n(.*?)^  ```", readme, re.S | re.M)]
    assert len(blocks) >= 3, blocks
    np.save(tmp_path / "volume.npy", blobs())
    prelude = ("import numpy as np, peakcast\nclient = peakcast.Client('http://localhost:8080')\n"
               "volume = np.load('volume.npy')\nvid = client.upload(volume)\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "client-python"))
    for code in blocks:
        code = (prelude + code).replace("http://localhost:8080", server.url)
        r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, env=env,
                           timeout=300)
        assert r.returncode == 0, (code, r.stderr)
