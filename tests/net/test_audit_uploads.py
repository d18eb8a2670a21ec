#!/usr/bin/env python3
"""An outside audit of the running server, held by the real server (one of four test_audit_*.py
files): one test (or a few) per point of the contract the fixes follow. This one: uploads. Names
that are valid UTF-8 and survive a restart, headers that cannot name another file, a minimum rate
and a whole-body deadline, the decoded size counted, a raw upload's size matching its dims, and a
deleted upload moving its viewer and freeing its memory. Fixtures are written here, into temporary
folders; traffic goes to 127.0.0.1 only; every wait is bounded. The helpers and fixtures are in
audit_util.py."""
import asyncio, json, os, pathlib, select, socket, sys, tempfile, time
import urllib.parse

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403
from audit_util import *  # noqa: F401,F403


# ---------------------------------------------------------------------------------------------
# 3. Upload names: valid UTF-8, cut at a character boundary; listed, viewed, deleted, and again
#    after a restart. A commit that fails leaves nothing.

RAW64 = voxels(64)  # 4x4x4 uint8


def test_3_upload_names_are_valid_utf8_and_survive_a_restart():
    with tempfile.TemporaryDirectory() as up:
        ids, names = {}, {}
        with serve("--upload-dir", up) as s:
            for label, q in (("ff", "name=%ff"), ("kana", "name=" + urllib.parse.quote(KANA))):
                for k in (0, 1):
                    status, _, body = upload(s, RAW64, f"dims=4,4,4&dtype=uint8&{q}")
                    try:
                        text = body.decode("utf-8")
                    except UnicodeDecodeError as e:
                        raise AssertionError(f"upload ?{q}: the answer is not valid UTF-8 ({e}): {body[:300]!r}")
                    assert status == 201, f"upload ?{q[:40]}: {status} {text[:300]}"
                    info = json.loads(text)
                    ids[(label, k)], names[(label, k)] = info["id"], info["name"]
            for k in (0, 1):
                assert "\ufffd" in names[("ff", k)], f"name=%ff kept as {names[('ff', k)]!r}: U+FFFD expected"
                n = names[("kana", k)]
                assert 0 < len(n.encode("utf-8")) <= 200 and n.startswith("データ"), \
                    f"the 211-byte name was kept as {len(n.encode())} bytes: {n!r}"
            assert health(s)["uploads"]["used_bytes"] >= 4 * 64, f"uploads not counted: {health(s)['uploads']}"
            listed = {v["id"]: v["name"] for v in listing(s)["volumes"]}
            for key, vid in ids.items():
                assert listed.get(vid) == names[key], f"upload {key} ({vid}) listed as {listed.get(vid)!r}"

            async def view(vid):
                c = await Client.connect(s)
                w = await c.hello(64, 48, volume=vid)
                assert w["volume"]["id"] == vid, w["volume"]
                await c.next_frame()
                await c.close()
            for key in (("ff", 0), ("kana", 0)):
                asyncio.run(view(ids[key]))
            for key in (("ff", 0), ("kana", 0)):
                status, _, body = delete(s, ids[key])
                assert status == 200, f"DELETE of upload {key}: {status} {body[:300]!r}"
            listed = {v["id"] for v in listing(s)["volumes"]}
            assert not {ids[("ff", 0)], ids[("kana", 0)]} & listed, "a deleted upload is still listed"
            healthy(s, "the uploads")
        kept = [ids[("ff", 1)], ids[("kana", 1)]]
        assert leftovers(up, kept) == [], f"files of deleted uploads left: {leftovers(up, kept)}"
        with serve("--upload-dir", up) as s:  # the same upload dir after a restart
            listed = {v["id"]: v["name"] for v in listing(s)["volumes"]}
            for key in (("ff", 1), ("kana", 1)):
                assert listed.get(ids[key]) == names[key], \
                    f"after a restart upload {key} is listed as {listed.get(ids[key])!r}, expected {names[key]!r}"
            asyncio.run(view(ids[("kana", 1)]))
            for key in (("ff", 1), ("kana", 1)):
                status, _, body = delete(s, ids[key])
                assert status == 200, f"after a restart, DELETE of upload {key}: {status} {body[:300]!r}"
            assert health(s)["uploads"]["used_bytes"] == 0, health(s)["uploads"]
            healthy(s, "deleting after a restart")
        assert leftovers(up) == [], f"files left in the upload dir: {leftovers(up)}"


def test_3_a_failed_commit_leaves_no_file_and_no_volume():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        cases = [("name=%ff", nrrd(data=b"short"), (422,)),  # truncated, with a name that is not UTF-8
                 ("name=" + urllib.parse.quote(KANA), nrrd(data=b"short"), (422,)),
                 ("name=%ff%fe", b"neither NRRD nor anything\n" * 4, (415,)),
                 ("name=%ff&dims=4,4,4&dtype=uint8", b"x" * 10, (400, 422))]
        for q, body_in, statuses in cases:
            status, _, body = upload(s, body_in, q)
            error_of(f"upload ?{q[:40]}", status, body, statuses)
            healthy(s, f"a failing upload ?{q[:40]}")
            assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], f"upload ?{q[:40]} is listed"
            assert leftovers(up) == [], f"upload ?{q[:40]} left files: {leftovers(up)}"
        assert health(s)["uploads"]["used_bytes"] == 0, health(s)["uploads"]


# ---------------------------------------------------------------------------------------------
# 4. An upload whose header names another file: 415 unsupported_upload, whatever the spelling.

def mha(lines, data=b""):
    return b"\n".join(lines) + b"\n" + data


MHA_HEAD = [b"ObjectType = Image", b"NDims = 3", b"DimSize = 2 2 2", b"ElementType = MET_UCHAR"]


def test_4_uploads_naming_another_file_are_refused():
    variants = {
        "MHA Comment, blank line, ElementDataFile": mha([b"Comment = x", b""] + MHA_HEAD + [b"ElementDataFile = /etc/passwd"]),
        "MHA ElementDataFile\\t=": mha(MHA_HEAD + [b"ElementDataFile\t= /etc/passwd"]),
        "MHA plain": mha(MHA_HEAD + [b"ElementDataFile = /etc/passwd"]),
        "NRRD 'data file :'": nrrd(sizes=(2, 2, 2), data=b"", extra=b"data file : /etc/passwd\n")[:-1],
        "NRRD ' data file:'": nrrd(sizes=(2, 2, 2), data=b"", extra=b" data file: /etc/passwd\n")[:-1],
        "NRRD 'DATA FILE:' after a comment": nrrd(sizes=(2, 2, 2), data=b"", extra=b"# c\nDATA FILE: /etc/passwd\n")[:-1],
    }
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        for what, body_in in variants.items():
            status, _, body = upload(s, body_in, "name=x")
            error_of(f"upload ({what})", status, body, 415, "unsupported_upload")
            assert b"root:" not in body, f"upload ({what}) answered the file's bytes"
            healthy(s, f"upload ({what})")
            assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], f"upload ({what}) is listed"
        # The message tells nothing of the named path: the same text, showing the path in the same
        # form (whole, its last name, or not at all), whether the file or its folder exists or not.
        seen = []
        for path in ("/etc/passwd", "/etc/zz-audit-none", "/zz-audit-dir/zz-audit-none"):
            body_in = mha([b"Comment = x", b""] + MHA_HEAD + [b"ElementDataFile = " + path.encode()])
            status, _, body = upload(s, body_in, "name=x")
            m = error_of(f"upload naming {path}", status, body, 415, "unsupported_upload")["message"]
            base = path.rsplit("/", 1)[1]
            form = "whole" if path in m else "last name" if base in m else "absent"
            seen.append((path, form, m.replace(path, "PATH").replace(base, "PATH"), m))
        assert len({(form, text) for _, form, text, _ in seen}) == 1, \
            "the refusal differs with the named path's existence:\n  " + "\n  ".join(f"{p}: {m}" for p, _, _, m in seen)
        size = str(os.path.getsize("/etc/passwd"))
        assert size not in seen[0][3], f"the refusal tells the named file's size: {seen[0][3]}"
        assert leftovers(up) == [], f"files left in the upload dir: {leftovers(up)}"


# ---------------------------------------------------------------------------------------------
# 6. Uploads have a minimum rate and a whole-body deadline.

def _drain_answer(c, buf, took):
    """What a connection the server closed still holds: (took, status, body), or status None."""
    try:
        c.settimeout(0.5)
        while True:
            data = c.recv(65536)
            if not data:
                break
            buf += data
    except OSError:
        pass
    got = parse_answer(buf, closed=True)
    return (took, got[0], got[2]) if got else (took, None, buf)


def _trickle(s, count, seconds, chunk=b"\0", every=1.0, length=1_000_000):
    """`count` uploads announcing `length` bytes, each sending `chunk` every `every` seconds:
    for each, (seconds until the server answered, status, body); status None when the server
    closed the connection without an answer; None when it did neither."""
    head = (f"POST /api/volumes?dims=100,100,100&dtype=uint8 HTTP/1.1\r\nHost: {s.host}:{s.port}\r\n"
            f"Content-Type: application/octet-stream\r\nContent-Length: {length}\r\n\r\n").encode()
    socks = []
    for _ in range(count):
        c = socket.create_connection((s.host, s.port), timeout=5)
        c.sendall(head)
        socks.append(c)
    t0, bufs, done, closed = time.time(), [b""] * count, [None] * count, [False] * count
    next_send = t0
    try:
        while time.time() - t0 < seconds and not all(d is not None or cl for d, cl in zip(done, closed)):
            if time.time() >= next_send:
                for i, c in enumerate(socks):
                    if done[i] is None and not closed[i]:
                        try:
                            c.sendall(chunk)
                        except OSError:  # the server hung up: read what it said first
                            closed[i] = True
                            done[i] = _drain_answer(c, bufs[i], time.time() - t0)
                next_send += every
            live = [c for i, c in enumerate(socks) if done[i] is None and not closed[i]]
            r, _, _ = select.select(live, [], [], max(0.0, min(0.2, next_send - time.time())))
            for c in r:
                i = socks.index(c)
                try:
                    data = c.recv(65536)
                except OSError:
                    data = b""
                bufs[i] += data
                got = parse_answer(bufs[i], closed=not data)
                if got:
                    done[i] = (time.time() - t0, got[0], got[2])
                elif not data:
                    closed[i] = True
                    done[i] = (time.time() - t0, None, bufs[i])
    finally:
        for c in socks:
            c.close()
    return done


def test_6_trickle_uploads_are_ended_as_too_slow():
    """--upload-timeout 2 --max-uploads 2: two uploads of 1,000,000 bytes sending a byte a second
    end with 408 upload_too_slow within ~5 s; an honest upload then gets 201 at once."""
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up, "--upload-timeout", "2", "--max-uploads", "2") as s:
        done = _trickle(s, 2, 7.0)
        for i, d in enumerate(done):
            assert d is not None, f"trickle upload {i}: no answer in 7 s (a byte a second kept it alive)"
            took, status, body = d
            assert status is not None, f"trickle upload {i}: closed after {took:.1f} s without an answer"
            error_of(f"trickle upload {i}", status, body, 408, "upload_too_slow")
            assert took < 5.5, f"trickle upload {i} was ended only after {took:.1f} s"
        status, _, body = upload(s, voxels(1_000_000), "dims=100,100,100&dtype=uint8", timeout=30)
        assert status == 201, f"an honest upload after the trickles: {status} {body[:300]!r}"
        healthy(s, "the trickle uploads")
        assert not [p for p in leftovers(up, [json.loads(body)["id"]])], leftovers(up)


def test_6_the_whole_body_has_a_deadline():
    """--upload-deadline 3 with a minimum rate of 1 KiB/s: an upload sending 10 KiB/s (fast enough)
    of 1,000,000 bytes is ended at the deadline with 408 upload_too_slow."""
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up, "--upload-timeout", "1", "--upload-min-rate-kib",
                                                    "1", "--upload-deadline", "3") as s:
        done = _trickle(s, 1, 7.0, chunk=bytes(4096), every=0.4)
        assert done[0] is not None, "an upload over its deadline: no answer in 7 s"
        took, status, body = done[0]
        assert status is not None, f"an upload over its deadline: closed after {took:.1f} s without the 408"
        error_of("an upload past --upload-deadline", status, body, 408, "upload_too_slow")
        assert 2.5 < took < 5.0, f"ended after {took:.1f} s (deadline 3 s)"
        status, _, body = upload(s, voxels(64), "dims=4,4,4&dtype=uint8")
        assert status == 201, f"an honest upload after: {status} {body[:300]!r}"
        healthy(s, "the upload past its deadline")


# ---------------------------------------------------------------------------------------------
# 8. An upload counts what it decodes to.

def test_8_a_gzip_upload_counts_its_decoded_bytes():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        status, _, body = upload(s, gzip_zeros_nrrd(), "name=zeros.nrrd")
        assert status == 201, f"the gzip NRRD of 400^3 zeros: {status} {body[:300]!r}"
        used = health(s)["uploads"]["used_bytes"]
        assert 64_000_000 <= used < 64_000_000 + (1 << 20), \
            f"uploads.used_bytes is {used} for a volume of 64,000,000 bytes ({len(gzip_zeros_nrrd())} sent)"
        healthy(s, "the gzip upload")


def test_8_a_gzip_upload_over_the_budget_is_refused_before_decoding():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up, "--upload-budget-mib", "32") as s:
        before = vm_kib(s, "VmHWM")
        status, _, body = upload(s, gzip_zeros_nrrd(), "name=zeros.nrrd")
        peak = vm_kib(s, "VmHWM")
        error_of("the gzip NRRD of 64,000,000 bytes under a 32 MiB budget", status, body, 507, "upload_budget")
        if not SANITIZED:
            assert peak - before < 48 * 1024, f"the peak RSS grew by {(peak - before) // 1024} MiB: decoded first"
        assert health(s)["uploads"]["used_bytes"] == 0, health(s)["uploads"]
        assert leftovers(up) == [], leftovers(up)
        healthy(s, "the upload over the budget")


# ---------------------------------------------------------------------------------------------
# 12. A raw upload's size must be its dims' size; every axis at least 2 voxels.

def test_12_a_raw_upload_with_extra_bytes_is_refused():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        status, _, body = upload(s, voxels(1000), "dims=5,10,10&dtype=uint8")
        j = error_of("raw dims=5,10,10 uint8 with 1000 bytes", status, body, 400, "bad_upload")
        assert "500" in j["message"] and "1000" in j["message"], f"the message must name 500 and 1000: {j['message']}"
        assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], "the refused upload is listed"
        status, _, body = upload(s, voxels(1000), "dims=10,10,10&dtype=uint8")
        assert status == 201, f"raw dims=10,10,10 with 1000 bytes: {status} {body[:300]!r}"
        assert leftovers(up, [json.loads(body)["id"]]) == [], leftovers(up)
        healthy(s, "the upload with extra bytes")


def test_12_a_raw_upload_needs_two_voxels_per_axis():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        for dims in ("1000,1,1", "1,1000,1", "10,100,1"):
            status, _, body = upload(s, voxels(1000), f"dims={dims}&dtype=uint8")
            error_of(f"raw dims={dims} uint8", status, body, 400, "bad_upload")
        assert not [v for v in listing(s)["volumes"] if v.get("uploaded")], "a refused upload is listed"
        assert leftovers(up) == [], leftovers(up)
        healthy(s, "the flat uploads")


# ---------------------------------------------------------------------------------------------
# 13. Deleting a viewed upload: the viewer hears it and moves on; the memory goes.

def test_13_a_deleted_upload_moves_its_viewer_and_frees_its_memory():
    with tempfile.TemporaryDirectory() as up, serve("--upload-dir", up) as s:
        h0 = health(s)
        assert "volume_bytes" in h0, f"/api/health has no volume_bytes: {sorted(h0)}"
        b0 = h0["volume_bytes"]
        default = listing(s)["default"]
        status, _, body = upload(s, voxels(64 ** 3), "dims=64,64,64&dtype=uint8&name=viewed")
        assert status == 201, f"upload: {status} {body[:300]!r}"
        vid = json.loads(body)["id"]

        async def run():
            c = await Client.connect(s)
            w = await c.hello(64, 48, volume=vid)
            assert w["volume"]["id"] == vid, w["volume"]
            await c.next_frame()
            b1 = health(s)["volume_bytes"]
            assert b1 >= b0 + 64 ** 3, f"volume_bytes {b1} while the upload is viewed (before: {b0})"
            status, _, body = delete(s, vid)
            assert status == 200, f"DELETE: {status} {body[:300]!r}"
            try:
                e = await c.next_text("error", timeout=10)
            except (TimeoutError, asyncio.TimeoutError):
                raise AssertionError(f"the viewer heard nothing of the deletion: {[m.get('type') for m in c.texts]}")
            assert e["code"] == "volume_deleted", e
            m = await c.next_text("volume", timeout=10)
            assert m["volume"]["id"] == default, f"the viewer was moved to {m['volume']['id']}, not {default}"
            await c.next_frame()
            await c.close()
        asyncio.run(run())
        deadline, b2 = time.time() + 5, None
        while time.time() < deadline:
            b2 = health(s)["volume_bytes"]
            if b2 <= b0:
                break
            time.sleep(0.1)
        assert b2 <= b0, f"volume_bytes {b2} after the delete; {b0} before the upload"
        healthy(s, "the deletion")


if __name__ == "__main__":
    run_tests([
        test_3_upload_names_are_valid_utf8_and_survive_a_restart, test_3_a_failed_commit_leaves_no_file_and_no_volume,
        test_4_uploads_naming_another_file_are_refused, test_6_trickle_uploads_are_ended_as_too_slow,
        test_6_the_whole_body_has_a_deadline, test_8_a_gzip_upload_counts_its_decoded_bytes,
        test_8_a_gzip_upload_over_the_budget_is_refused_before_decoding,
        test_12_a_raw_upload_with_extra_bytes_is_refused, test_12_a_raw_upload_needs_two_voxels_per_axis,
        test_13_a_deleted_upload_moves_its_viewer_and_frees_its_memory,
    ])
