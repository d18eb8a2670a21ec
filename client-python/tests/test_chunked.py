"""Arrays past the server's memory budget, sent chunk by chunk: a numpy memmap, a zarr array and a
dask array arrive exactly (the pyramid's level 0 read back by python3-zarr, independent of the
server's reader), the client reads one chunk at a time, progress is told, the volume opens at a
level the budget holds and renders; an interrupted upload resumes with only the missing chunks;
a removed one leaves no file; each refusal is a clear error."""
import json
import urllib.error
import urllib.request

import numpy as np
import pytest
import zarr

from conftest import Server, blobs
import peakcast

SHAPE = (40, 150, 200)  # z, y, x: 2.3 MiB of uint16, past the 1 MiB budget


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """A memory budget of 1 MiB: every array here is past it."""
    s = Server(tmp_path_factory.mktemp("chunked"), "--memory-budget-mib", "1", "--max-upload-mib", "64",
               "--upload-budget-mib", "64", "--uploads-per-minute", "60000")
    yield s
    s.stop()


def field(shape=SHAPE, dtype=np.uint16):
    return blobs(shape, dtype)


class Watched:
    """An array that records the largest block read from it, and can fail at its n-th read."""

    def __init__(self, a, fail_at=None):
        self.a, self.shape, self.dtype, self.largest, self.reads, self.fail_at = a, a.shape, a.dtype, 0, 0, fail_at

    def __getitem__(self, key):
        self.reads += 1
        if self.fail_at is not None and self.reads == self.fail_at:
            raise ConnectionError("the script's data went away")
        b = np.asarray(self.a[key])
        self.largest = max(self.largest, b.nbytes)
        return b


def level0(server, vid):
    return zarr.open(str(server.upload_dir / f"{vid}.zarr"), mode="r")["0"][...]


def test_a_memmap_past_the_budget_arrives_exactly_and_renders(small, tmp_path):
    a = np.lib.format.open_memmap(tmp_path / "big.npy", "w+", np.uint16, SHAPE)
    a[...] = field()
    c = peakcast.Client(small.url)
    seen = []
    w = Watched(a)
    vid = c.upload_chunked(w, spacing=(0.5, 0.5, 2.0), units="um", chunk=(8, 64, 64), name="memmap",
                           progress=lambda done, total, stage: seen.append((done, total, stage)))
    assert w.largest <= 8 * 64 * 64 * 2, f"the client read a block of {w.largest} bytes, past one chunk"
    chunks = 5 * 3 * 4
    assert [s for s in seen if s[2] == "sending"] == [(k, chunks, "sending") for k in range(1, chunks + 1)]
    assert seen[-1] == (chunks, chunks, "done")
    assert np.array_equal(level0(small, vid), a), "level 0 is not the array"
    info = c.volume(vid)
    assert info["full_dims"] == [200, 150, 40] and info["level"] >= 1 and info["units"] == "µm", info
    assert info["spacing"] == [0.5 * 2 ** info["level"], 0.5 * 2 ** info["level"], 2.0 * 2 ** info["level"]], info
    image = c.render({"volume": vid, "image": {"width": 96, "height": 64}})
    assert image.shape == (64, 96, 3) and image.max() > 10, "it did not render"
    assert not [f for f in small.files() if f.startswith(".incoming")], "the chunks' file outlived the build"
    c.delete(vid)


def test_zarr_and_dask_arrays_are_read_a_chunk_at_a_time(small):
    import dask.array as da
    c = peakcast.Client(small.url)
    z = zarr.zeros(SHAPE, chunks=(10, 75, 100), dtype=np.int16)
    z[...] = field(dtype=np.int16) // 3
    vid = c.upload_chunked(z)
    assert c._http.request("GET", f"/api/uploads/{vid}")[0] == 200
    status = json.loads(c._http.request("GET", f"/api/uploads/{vid}")[2])
    assert status["chunk"] == [100, 75, 10] and status["chunks"] == 16, "the zarr array's own chunks"
    assert np.array_equal(level0(small, vid), z[...])
    c.delete(vid)
    d = da.from_array(field(dtype=np.float32) / 7, chunks=(20, 150, 100)).astype(np.float64)  # float64: sent as float32
    vid = c.upload_chunked(d)
    assert np.array_equal(level0(small, vid), d.compute().astype(np.float32))
    c.delete(vid)


def test_an_interrupted_upload_resumes_with_the_chunks_missing(small):
    c = peakcast.Client(small.url)
    a = field()
    with pytest.raises(peakcast.UploadInterrupted) as e:
        c.upload_chunked(Watched(a, fail_at=7), chunk=(20, 75, 100))  # 8 chunks: 6 arrive
    assert e.value.sent == 6 and e.value.chunks == 8, e.value
    status = json.loads(c._http.request("GET", f"/api/uploads/{e.value.upload_id}")[2])
    assert status["state"] == "receiving" and status["received"] == 6, status
    sent = []
    vid = c.upload_chunked(a, resume=e.value.upload_id, progress=lambda d, t, s: sent.append(s))
    assert sent.count("sending") == 2, "a resume sends only what did not arrive"
    assert np.array_equal(level0(small, vid), a)
    with pytest.raises(ValueError):  # another array cannot resume it
        c.upload_chunked(a[:, :, :100], resume=vid)
    c.delete(vid)


def test_a_removed_upload_leaves_nothing(small):
    c = peakcast.Client(small.url)
    with pytest.raises(peakcast.UploadInterrupted) as e:
        c.upload_chunked(Watched(field(), fail_at=3), chunk=(20, 75, 100))
    assert any(f.startswith(".incoming/") for f in small.files()), "the chunks so far are on disk"
    req = urllib.request.Request(f"{small.url}/api/uploads/{e.value.upload_id}", method="DELETE")
    assert urllib.request.urlopen(req).status == 200
    assert small.files() == [], small.files()
    with pytest.raises(peakcast.ServerError) as gone:
        c._http.request("GET", f"/api/uploads/{e.value.upload_id}")
    assert gone.value.status == 404


def post(server, path, body=b"", method="POST"):
    req = urllib.request.Request(server.url + path, data=body, method=method)
    try:
        with urllib.request.urlopen(req) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def test_refusals_are_clear(small):
    decl = {"dims": [20, 20, 20], "dtype": "uint16", "chunk": [10, 10, 10]}
    bad = [({**decl, "dtype": "float64"}, 400, "dtype"), ({**decl, "dims": [20, 20]}, 400, "dims"),
           ({**decl, "dims": [4096, 4096, 2], "chunk": [4096, 4096, 1]}, 400, "16 MiB"), ({**decl, "size": 3}, 400, "unknown key 'size'"),
           ({**decl, "dims": [4000, 4000, 4000]}, 413, "MiB"), ({**decl, "spacing": [0, 1, 1]}, 400, "spacing")]
    for body, code, words in bad:
        status, answer = post(small, "/api/uploads", json.dumps(body).encode())
        assert status == code and words in answer["message"], (body, status, answer)
    status, answer = post(small, "/api/uploads", json.dumps(decl).encode())
    assert status == 201, answer
    uid = answer["id"]
    assert post(small, f"/api/uploads/{uid}/chunks/0/0/0", b"x" * 10, "PUT")[0] == 400  # the wrong size
    status, answer = post(small, f"/api/uploads/{uid}/chunks/2/0/0", bytes(2000), "PUT")
    assert status == 400 and "outside the grid of 2x2x2" in answer["message"], answer
    assert post(small, f"/api/uploads/{uid}/chunks/1/1/1", bytes(2000), "PUT")[0] == 200
    status, answer = post(small, f"/api/uploads/{uid}/finish")
    assert status == 409 and "7 of 8 chunks have not arrived" in answer["message"], answer
    assert post(small, "/api/uploads/upload-000000000000", b"", "GET")[0] == 404
    assert post(small, f"/api/uploads/{uid}", b"", "DELETE")[0] == 200
    with pytest.raises(ValueError):
        peakcast.Client(small.url).upload_chunked(np.zeros((2, 3, 4, 5), np.uint8))
    with pytest.raises(ValueError):
        peakcast.Client(small.url).upload_chunked(np.zeros((4, 4, 4), np.complex64))
    assert small.files() == [], small.files()


def test_chunked_uploads_need_the_token(guarded):
    decl = json.dumps({"dims": [4, 4, 4], "dtype": "uint8", "chunk": [4, 4, 4]}).encode()
    for method, path in (("POST", "/api/uploads"), ("GET", "/api/uploads/upload-000000000001"),
                         ("PUT", "/api/uploads/upload-000000000001/chunks/0/0/0")):
        status, answer = post(guarded, path, decl, method)
        assert status == 401 and answer["error"] == "unauthorized", (method, path, status, answer)
    vid = peakcast.Client(guarded.url, token="sesame").upload_chunked(np.arange(64, dtype=np.uint8).reshape(4, 4, 4))
    assert np.array_equal(zarr.open(str(guarded.upload_dir / f"{vid}.zarr"), mode="r")["0"][...],
                          np.arange(64, dtype=np.uint8).reshape(4, 4, 4))


def test_another_web_page_cannot_begin_one(small):
    req = urllib.request.Request(small.url + "/api/uploads", method="POST", headers={"Origin": "http://evil.example"},
                                 data=json.dumps({"dims": [4, 4, 4], "dtype": "uint8", "chunk": [4, 4, 4]}).encode())
    with pytest.raises(urllib.error.HTTPError) as e:
        urllib.request.urlopen(req)
    assert e.value.code == 403 and b"forbidden_origin" in e.value.read()
    assert small.files() == []


def test_a_finished_upload_takes_no_more_chunks(small):
    c = peakcast.Client(small.url)
    vid = c.upload_chunked(np.arange(64, dtype=np.uint8).reshape(4, 4, 4))
    status, answer = post(small, f"/api/uploads/{vid}/chunks/0/0/0", bytes(64), "PUT")
    assert status == 409 and answer["error"] == "upload_finished", answer
    status, answer = post(small, f"/api/uploads/{vid}/finish")
    assert status == 409 and answer["error"] == "upload_finished", answer
    c.delete(vid)
