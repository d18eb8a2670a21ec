"""Movies through the client: movie() writes the streamed file (its format from the suffix),
movie_frames() yields each frame as an Image equal to the still of its camera, refusals raise
before anything is written, and a script that stops iterating ends the movie on the server."""
import json
import math
import time
import urllib.request
import zipfile

import numpy as np
import pytest

from conftest import blobs
import peakcast

SCENE = {"image": {"width": 64, "height": 48}, "render": {"classification": "post"}}


@pytest.fixture(scope="module")
def vid(server):
    c = peakcast.Client(server.url)
    v = c.upload(blobs(), name="movie")
    yield v
    c.delete(v)


def test_movie_writes_the_file_as_its_suffix_says(server, vid, tmp_path):
    c = peakcast.Client(server.url)
    scene = dict(SCENE, volume=vid)
    info = c.movie(scene, tmp_path / "o.mp4", orbit={"degrees": 360}, frames=6, fps=12)
    data = (tmp_path / "o.mp4").read_bytes()
    assert data[4:8] == b"ftyp" and info.bytes == len(data) and info.format == "mp4", info
    assert (info.frames, info.fps, info.width, info.height, info.encoder) == (6, 12, 64, 48, "libx264"), info
    info = c.movie(scene, tmp_path / "o.zip", orbit={"degrees": 360}, frames=3)
    assert info.format == "png-zip" and len(zipfile.ZipFile(tmp_path / "o.zip").namelist()) == 3
    info = c.movie(scene, tmp_path / "o.webm", keys=[{}, {}], frames=2)
    assert (tmp_path / "o.webm").read_bytes()[:4] == b"\x1a\x45\xdf\xa3" and info.encoder == "libvpx-vp9"


def test_movie_frames_are_the_stills_of_their_cameras(server, vid):
    c = peakcast.Client(server.url)
    cam = {"eye": [14, 12, 90], "center": [14, 12, 10], "up": [0, 1, 0]}
    scene = dict(SCENE, volume=vid, camera=cam)
    frames = list(c.movie_frames(scene, orbit={"axis": [0, 1, 0], "degrees": 90}, frames=3))
    assert len(frames) == 3 and all(f.shape == (48, 64, 3) and f.dtype == np.uint8 for f in frames)
    for i, frame in enumerate(frames):  # 0, 45, 90 degrees about +y through the focal point
        a = math.radians(45 * i)
        eye = [14 + 80 * math.sin(a), 12, 10 + 80 * math.cos(a)]
        still = c.render(dict(scene, camera=dict(cam, eye=eye)))
        # The same renderer and TF; the camera's arithmetic differs in the last bits (server: C++).
        assert np.abs(frame.astype(int) - still.astype(int)).max() <= 1, f"frame {i}"
    assert frames[0].tf_source == "auto" and frames[0].level == 0  # what the server said rides along


def test_refusals_raise_before_anything_is_written(server, vid, tmp_path):
    c = peakcast.Client(server.url)
    with pytest.raises(peakcast.ServerError) as e:
        c.movie(dict(SCENE, volume=vid), tmp_path / "x.mp4", orbit={"degrees": 90}, frames=0)
    assert e.value.status == 400 and "frames" in e.value.message
    assert not (tmp_path / "x.mp4").exists(), "a refused movie left a file"
    with pytest.raises(ValueError):
        c.movie(dict(SCENE, volume=vid), tmp_path / "y.mp4")  # neither orbit nor keys
    with pytest.raises(peakcast.ServerError) as e:
        list(c.movie_frames(dict(SCENE, volume="no-such-volume"), orbit={}, frames=2))
    assert e.value.status == 404


def test_stopping_the_frames_ends_the_movie(server, vid):
    c = peakcast.Client(server.url)
    scene = dict(SCENE, volume=vid, image={"width": 128, "height": 128}, render={"step": 0.1})
    frames = c.movie_frames(scene, orbit={"degrees": 360}, frames=2000)
    next(frames)
    frames.close()  # the connection closes with the generator
    deadline = time.time() + 60
    while time.time() < deadline:
        with urllib.request.urlopen(server.url + "/metrics") as r:
            if b'peakcast_movies_total{outcome="cancelled"}' in r.read():
                break
        time.sleep(0.2)
    else:
        raise AssertionError("the server went on drawing a movie nobody reads")
    while time.time() < deadline:  # its frame in flight stops at its next band
        with urllib.request.urlopen(server.url + "/api/health") as r:
            if json.loads(r.read())["stills_queued"] == 0:
                break
        time.sleep(0.2)
    else:
        raise AssertionError("the movie's stills stayed queued")
