#!/usr/bin/env python3
"""An outside audit of the running server, held by the real server (one of four test_audit_*.py
files): one test (or a few) per point of the contract the fixes follow. This one: the data
directories. Chunked readers that refuse before they read or decode too much, links out of the data
directories refused at every open, no server path in any answer (REST or WS), and file names that
are not UTF-8 listed without error. Fixtures are written here, into temporary folders; traffic goes
to 127.0.0.1 only; every wait is bounded. The helpers and fixtures are in audit_util.py."""
import asyncio, json, os, pathlib, sys, tempfile, threading, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403
from audit_util import *  # noqa: F401,F403


# ---------------------------------------------------------------------------------------------
# 7. Chunked readers refuse before they probe or decode too much.

PRECOMPUTED = json.dumps({"type": "image", "data_type": "uint8", "num_channels": 1, "scales": [
    {"key": "s0", "size": [4096, 4096, 1], "resolution": [1, 1, 1], "voxel_offset": [0, 0, 0],
     "chunk_sizes": [[1, 1, 1]], "encoding": "raw"}]})


def test_7_precomputed_with_millions_of_chunks_is_refused_at_once():
    """A Neuroglancer `info` of 4096x4096x1 in 1x1x1 chunks (16.7 M missing chunks): refused in
    under 2 s; /api/files answers within 1 s while it and another volume load."""
    with tempfile.TemporaryDirectory() as tmp:
        pathlib.Path(tmp, "pre").mkdir()
        pathlib.Path(tmp, "pre", "info").write_text(PRECOMPUTED)
        pathlib.Path(tmp, "pre", "s0").mkdir()
        pathlib.Path(tmp, "zeros.nrrd").write_bytes(gzip_zeros_nrrd())
        with serve("--data", tmp, volumes=()) as s:
            answers = {}

            def load(vol):
                t0 = time.time()
                try:
                    st, _, b = render(s, vol)
                    answers[vol] = (time.time() - t0, st, b)
                except Exception as e:  # noqa: BLE001
                    answers[vol] = (time.time() - t0, None, repr(e).encode())
            # "pre" first: the loader is one thread, and the refusal is timed, not the wait behind
            # the 64 MB gzip volume (seconds under a sanitizer).
            threads = [threading.Thread(target=load, args=(v,), daemon=True) for v in ("pre", "zeros.nrrd")]
            for t in threads:
                t.start()
                time.sleep(0.05)
            t0 = time.time()
            try:
                status, _, body = raw(s, "GET", "/api/files", timeout=5)
            except TimeoutError:
                raise AssertionError("/api/files: no answer within 5 s while volumes load")
            took = time.time() - t0
            assert status == 200, f"/api/files: {status} {body[:200]!r}"
            assert took < 1.0, f"/api/files took {took:.1f} s while volumes loaded"
            slow = 4 if SANITIZED else 1  # a sanitizer's server starts, parses and answers more slowly
            threads[0].join(4 * slow)
            assert "pre" in answers, f"the precomputed volume: no answer within {4 * slow} s"
            took, status, body = answers["pre"]
            assert status is not None, f"the precomputed volume: {body!r}"
            error_of("the precomputed volume of 16.7 M chunks", status, body, tuple(range(400, 500)))
            assert took < 2.0 * slow, f"the precomputed volume was refused only after {took:.1f} s"
            threads[1].join(30)
            healthy(s, "the precomputed volume")


def test_7_zarr_chunks_that_decode_past_the_budget_are_refused_before_decoding():
    """A zarr array of 8x64x64 in chunks of 2x16384x16384 (zstd, 16 KB each, 512 MiB decoded)
    under --memory-budget-mib 64: refused, and the server's RSS stays below 300 MB."""
    with tempfile.TemporaryDirectory() as tmp:
        z = pathlib.Path(tmp, "big.zarr")
        z.mkdir()
        (z / ".zarray").write_text(zarray([8, 64, 64], [2, 16384, 16384], {"id": "zstd", "level": 1}))
        chunk = zstd_zeros(2 * 16384 * 16384)
        assert len(chunk) < 1 << 20, len(chunk)
        for k in range(4):
            (z / f"{k}.0.0").write_bytes(chunk)
        with serve("--data", tmp, "--memory-budget-mib", "64", volumes=()) as s:
            before = vm_kib(s, "VmHWM")
            status, _, body = render(s, "big.zarr")
            peak = vm_kib(s, "VmHWM")
            print(f"  peak RSS {before // 1024} MiB before, {peak // 1024} MiB after the request")
            error_of("a zarr whose chunks decode to 512 MiB", status, body, tuple(range(400, 500)))
            if not SANITIZED:
                assert peak < 300 * 1024, f"the server's peak RSS reached {peak // 1024} MiB"
            healthy(s, "the zarr of 512 MiB chunks")


# ---------------------------------------------------------------------------------------------
# 9. Links out of the data directories are refused at every open.

def _links_fixture(tmp):
    data, out = pathlib.Path(tmp, "data"), pathlib.Path(tmp, "outside")
    data.mkdir()
    out.mkdir()
    (out / "secret.bin").write_bytes(bytes([200]) * 512)
    # A zarr array read through a chunk, a metadata file, or a level folder that lie outside.
    for name in ("ok.zarr", "chunk_link.zarr", "meta_link.zarr"):
        (data / name).mkdir()
    (data / "ok.zarr" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    (data / "ok.zarr" / "0.0.0").write_bytes(voxels(512))
    (data / "chunk_link.zarr" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    os.symlink(out / "secret.bin", data / "chunk_link.zarr" / "0.0.0")
    (out / "meta").mkdir()
    (out / "meta" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    os.symlink(out / "meta" / ".zarray", data / "meta_link.zarr" / ".zarray")
    (data / "meta_link.zarr" / "0.0.0").write_bytes(voxels(512))
    (out / "level0").mkdir()
    (out / "level0" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
    (out / "level0" / "0.0.0").write_bytes(bytes([200]) * 512)
    for name, level in (("ok_levels.zarr", None), ("level_link.zarr", out / "level0")):
        (data / name).mkdir()
        (data / name / ".zattrs").write_text(ZATTRS)
        if level is None:
            (data / name / "0").mkdir()
            (data / name / "0" / ".zarray").write_text(zarray([8, 8, 8], [8, 8, 8]))
            (data / name / "0" / "0.0.0").write_bytes(voxels(512))
        else:
            os.symlink(level, data / name / "0")
    # Detached NRRD headers whose data file lies outside: absolute, ../, and a link to outside.
    (data / "ok.raw").write_bytes(voxels(512))
    (data / "ok.nhdr").write_bytes(nhdr("ok.raw"))
    (data / "abs.nhdr").write_bytes(nhdr(str(out / "secret.bin")))
    (data / "rel.nhdr").write_bytes(nhdr("../outside/secret.bin"))
    os.symlink(out / "secret.bin", data / "linked.raw")
    (data / "via_link.nhdr").write_bytes(nhdr("linked.raw"))
    return data, out


def _expect_links_refused(refused, controls):
    with tempfile.TemporaryDirectory() as tmp:
        data, out = _links_fixture(tmp)
        with serve("--data", str(data), volumes=()) as s:
            for vol in controls:
                status, _, body = render(s, vol)
                assert status == 200, f"{vol} (all inside the data dir) must open: {status} {body[:300]!r}"
            for vol in refused:
                status, _, body = render(s, vol)
                error_of(f"{vol} (reads a file outside the data dirs)", status, body, tuple(range(400, 500)))
                assert_no_paths([(vol, body)], server_paths(tmp))
                listed = {v["id"] for v in listing(s)["volumes"]}
                assert vol not in listed, f"{vol} was opened and is listed"
                healthy(s, vol)


def test_9_a_zarr_chunk_or_metadata_linked_outside_is_refused():
    _expect_links_refused(["chunk_link.zarr", "meta_link.zarr"], ["ok.zarr"])


def test_9_a_zarr_level_folder_linked_outside_is_refused():
    _expect_links_refused(["level_link.zarr"], ["ok_levels.zarr"])


def test_9_an_nhdr_data_file_outside_is_refused():
    _expect_links_refused(["abs.nhdr", "rel.nhdr", "via_link.nhdr"], ["ok.nhdr"])


# ---------------------------------------------------------------------------------------------
# 10. No server path in any answer (REST or WS); a volume id never carries a path.

def test_10_errors_name_no_server_path():
    """A `.zarray` symlink loop, a ray texture naming an `.nhdr`: over REST and WS, no answer
    shows the data dirs' paths."""
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp)
        (d / "loop.zarr").mkdir()
        os.symlink(".zarray", d / "loop.zarr" / ".zarray")
        (d / "loop2.zarr").mkdir()
        os.symlink("b", d / "loop2.zarr" / ".zarray")
        os.symlink(".zarray", d / "loop2.zarr" / "b")
        (d / "loop3.zarr" / "0").mkdir(parents=True)
        (d / "loop3.zarr" / ".zattrs").write_text(ZATTRS)
        os.symlink(".zarray", d / "loop3.zarr" / "0" / ".zarray")
        (d / "sub").mkdir()
        (d / "sub" / "y.raw").write_bytes(voxels(512))
        (d / "sub" / "y.nhdr").write_bytes(nhdr("y.raw"))
        texts = []
        with serve("--data", tmp) as s:
            for vol in ("loop.zarr", "loop2.zarr", "loop3.zarr", "loop.zarr/.zarray"):
                status, _, body = render(s, vol)
                texts.append((f"render {vol}", body))
                error_of(f"render {vol}", status, body, tuple(range(400, 600)))
                healthy(s, f"render {vol}")
            for png in ("nucleon.nhdr", "sub/y.nhdr", "sub"):
                extra = {"render": {"ray_texture": {"mapping": "view", "png": png}}}
                status, _, body = render(s, "heptane_151", extra=extra)
                texts.append((f"render with ray_texture.png {png}", body))
                error_of(f"render with ray_texture.png {png}", status, body, tuple(range(400, 600)))
                scene = {"volume": "heptane_151", "image": {"width": 16, "height": 16}, "pixel": [8, 8], **extra}
                status, _, body = http(s, "/api/probe", "POST", json.dumps(scene).encode(), timeout=30)
                texts.append((f"probe with ray_texture.png {png}", body))
                error_of(f"probe with ray_texture.png {png}", status, body, tuple(range(400, 600)))

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48)
                for vol in ("loop.zarr", "loop3.zarr"):
                    await c.send({"type": "volume", "volume": vol})
                    e = await c.next_text("error", timeout=30)
                    texts.append((f"WS volume {vol}", json.dumps(e)))
                for png in ("nucleon.nhdr", "sub/y.nhdr"):
                    await c.send({"type": "render", "render": {"ray_texture": {"mapping": "view", "png": png}}})
                    e = await c.next_text("error", timeout=30)
                    texts.append((f"WS ray_texture.png {png}", json.dumps(e, ensure_ascii=False)))
                await c.close()
                texts.extend(ws_texts(c))
            asyncio.run(ws())
            healthy(s, "the errors")
        assert_no_paths(texts, server_paths(tmp))


def test_10_a_damaged_upload_after_a_restart_names_no_path():
    with tempfile.TemporaryDirectory() as up:
        with serve("--upload-dir", up) as s:
            status, _, body = upload(s, nrrd(), "name=scan.nrrd")
            assert status == 201, f"upload: {status} {body[:300]!r}"
            vid = json.loads(body)["id"]
        data = [p for p in pathlib.Path(up).iterdir() if p.name.startswith(vid + ".") and not p.name.endswith(".json")]
        assert len(data) == 1, f"the upload's data file: {[p.name for p in pathlib.Path(up).iterdir()]}"
        data[0].write_bytes(data[0].read_bytes()[:100])  # damaged while the server was down
        texts = []
        with serve("--upload-dir", up) as s:
            texts.append(("GET /api/volumes", http(s, "/api/volumes")[2]))
            status, _, body = http(s, f"/api/volumes/{vid}", timeout=30)
            texts.append((f"GET /api/volumes/{vid}", body))
            error_of(f"GET /api/volumes/{vid} (damaged)", status, body, tuple(range(400, 600)))
            status, _, body = render(s, vid)
            texts.append((f"render {vid}", body))
            error_of(f"render {vid} (damaged)", status, body, tuple(range(400, 600)))

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48)
                await c.send({"type": "volume", "volume": vid})
                e = await c.next_text("error", timeout=30)
                texts.append(("WS volume (damaged upload)", json.dumps(e, ensure_ascii=False)))
                await c.close()
                c2 = await Client.connect(s)
                await c2.send({"type": "hello", "viewport": {"width": 64, "height": 48}, "volume": vid})
                e = await c2.next_text("error", timeout=30)
                texts.append(("WS hello (damaged upload)", json.dumps(e, ensure_ascii=False)))
                await c2.close()
                texts.extend(ws_texts(c) + ws_texts(c2))
            asyncio.run(ws())
            healthy(s, "the damaged upload")
        assert_no_paths(texts, server_paths(up))


def test_10_a_volume_opened_by_absolute_path_gets_a_relative_id():
    with tempfile.TemporaryDirectory() as tmp:
        d = pathlib.Path(tmp)
        (d / "sub").mkdir()
        (d / "sub" / "x.nrrd").write_bytes(nrrd())
        (d / "x.nrrd").write_bytes(nrrd(sizes=(8, 8, 4), data=voxels(256)))
        texts = []
        with serve("--data", tmp) as s:
            status, headers, body = render(s, f"{tmp}/sub/x.nrrd")
            assert status == 200, f"render by absolute path inside a data dir: {status} {body[:300]!r}"
            texts.append(("render headers", json.dumps(headers)))
            vols = listing(s)
            texts.append(("GET /api/volumes", json.dumps(vols, ensure_ascii=False)))
            ids = [v["id"] for v in vols["volumes"]]
            assert "sub/x.nrrd" in ids and not [i for i in ids if i.startswith("/")], \
                f"the volume opened by absolute path is listed as {ids}"

            async def ws():
                c = await Client.connect(s)
                await c.hello(64, 48)
                await c.send({"type": "volume", "volume": f"{tmp}/x.nrrd"})
                m = await c.next_text("volume", timeout=30)
                assert m["volume"]["id"] == "x.nrrd", f"WS volume by absolute path got the id {m['volume']['id']!r}"
                await c.close()
                texts.extend(ws_texts(c))
                c2 = await Client.connect(s)
                w = await c2.hello(64, 48)
                assert not [v["id"] for v in w["volumes"] if v["id"].startswith("/")], w["volumes"]
                texts.append(("WS welcome", json.dumps(w, ensure_ascii=False)))
                await c2.close()
            asyncio.run(ws())
            texts.append(("GET /api/volumes (after WS)", http(s, "/api/volumes")[2]))
            healthy(s, "the volumes opened by absolute path")
        assert_no_paths(texts, server_paths(tmp))


# ---------------------------------------------------------------------------------------------
# 11. A file name that is not UTF-8 in a listed folder.

def test_11_a_file_name_that_is_not_utf8_is_listed_without_error():
    with tempfile.TemporaryDirectory() as tmp:
        sub = pathlib.Path(tmp, "sub")
        sub.mkdir()
        (sub / "ok.raw").write_bytes(voxels(512))
        (sub / "ok.nhdr").write_bytes(nhdr("ok.raw"))
        with open(os.path.join(os.fsencode(str(sub)), b"bad\xff.nhdr"), "wb") as f:
            f.write(nhdr("ok.raw"))
        os.mkdir(os.path.join(os.fsencode(tmp), b"dir\xfe"))
        with serve("--data", tmp, volumes=()) as s:
            for q in ("sub", ""):
                status, _, body = http(s, f"/api/files?dir={q}", timeout=30)
                try:
                    text = body.decode("utf-8")
                except UnicodeDecodeError as e:
                    raise AssertionError(f"/api/files?dir={q} is not valid UTF-8 ({e})")
                assert status == 200, f"/api/files?dir={q}: {status} {text[:300]}"
                names = [e["name"] for e in json.loads(text)["entries"]]
                assert ("ok.nhdr" if q else "sub") in names, f"/api/files?dir={q}: {names}"
            healthy(s, "the listing")


if __name__ == "__main__":
    run_tests([
        test_7_precomputed_with_millions_of_chunks_is_refused_at_once,
        test_7_zarr_chunks_that_decode_past_the_budget_are_refused_before_decoding,
        test_9_a_zarr_chunk_or_metadata_linked_outside_is_refused,
        test_9_a_zarr_level_folder_linked_outside_is_refused, test_9_an_nhdr_data_file_outside_is_refused,
        test_10_errors_name_no_server_path, test_10_a_damaged_upload_after_a_restart_names_no_path,
        test_10_a_volume_opened_by_absolute_path_gets_a_relative_id,
        test_11_a_file_name_that_is_not_utf8_is_listed_without_error,
    ])
