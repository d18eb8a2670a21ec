#!/usr/bin/env python3
"""DICOM series on the running server: the data browser lists a series folder as one volume with
its description (a folder of two series as two), both render by REST, GET /api/volumes carries
modality, description and value_unit HU, a ZIP of a series uploads and opens (entry names that
try to leave the folder reach nothing; a ZIP that says it decodes past the budget is refused
before anything is written; a ZIP of no DICOM slices is refused), and no patient identifier
appears in any answer or in the server's log. Series written by pydicom (tests/unit/dicom_fixtures.py)."""
import io, json, os, pathlib, sys, tempfile, urllib.parse, zipfile

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parent))
sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "unit"))
from harness import *  # noqa: F401,F403
from audit_util import serve, upload, listing, render  # noqa: E402
from dicom_fixtures import PATIENT_ID, PATIENT_NAME, write_series  # noqa: E402

IDENTIFIERS = (PATIENT_NAME, "DOE", PATIENT_ID)


def ct_stack():
    k, j, i = np.meshgrid(np.arange(6), np.arange(8), np.arange(8), indexing="ij")
    return (1024 + 200 * k + 10 * j + i - 500).astype(np.int16)  # HU -500 .. 577 after the intercept -1024


def make_links(root, outside):
    """A folder of the data directory whose slices are links to a series outside it."""
    write_series(os.path.join(outside, "secret"), ct_stack()[:2], positions=[(0, 0, k) for k in range(2)],
                 series_uid="1.2.3.6.9", description="Outside")
    os.makedirs(os.path.join(root, "leak"))
    for f in os.listdir(os.path.join(outside, "secret")):
        os.symlink(os.path.join(outside, "secret", f), os.path.join(root, "leak", f))


def make_data(root):
    write_series(os.path.join(root, "chest"), ct_stack(), positions=[(0, 0, 2.0 * k) for k in range(6)],
                 series_uid="1.2.3.6.1", description="Chest 2.0", intercept=-1024, spacing=(0.5, 0.5))
    two = os.path.join(root, "two")
    write_series(two, ct_stack()[:3], positions=[(0, 0, k) for k in range(3)], series_uid="1.2.3.6.2",
                 description="Soft tissue", seed=4)
    write_series(two, ct_stack()[:4], positions=[(0, 0, k) for k in range(4)], series_uid="1.2.3.6.3",
                 description="Bone", seed=5)


def zip_of(folder, rename=lambda n: n):
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for name in sorted(os.listdir(folder)):
            z.write(os.path.join(folder, name), rename(name))
        z.writestr("__MACOSX/._junk", b"resource fork")
    return out.getvalue()


def no_identifiers(texts):
    for what, text in texts:
        text = text.decode("utf-8", "replace") if isinstance(text, bytes) else text
        for ident in IDENTIFIERS:
            assert ident not in text, f"{what} shows the patient identifier {ident!r}"


def test_series_listed_rendered_uploaded_and_anonymous():
    with tempfile.TemporaryDirectory() as data, tempfile.TemporaryDirectory() as up, \
            tempfile.TemporaryDirectory() as outside:
        make_data(data)
        make_links(data, outside)
        with serve("--data", data, "--upload-dir", up, "--upload-budget-mib", "4") as s:
            said = []
            status, _, body = http(s, "/api/files?dir=")
            said.append(("the listing", body))
            assert status == 200, body[:300]
            entries = {e["name"]: e for e in json.loads(body)["entries"]}
            chest = entries.get("chest")
            assert chest and chest["kind"] == "volume" and chest["format"] == "dicom", entries
            assert chest["description"] == "Chest 2.0" and chest["dims"] == [8, 8, 6], chest
            assert entries["two#Bone"]["path"] == "two#1.2.3.6.3", entries.keys()
            assert entries["two#Soft tissue"]["path"] == "two#1.2.3.6.2", entries.keys()
            # Slices that are links out of the data directories: not listed as a series, not read.
            assert entries.get("leak", {}).get("format") != "dicom", entries.get("leak")
            for vol in ("leak", "leak#1.2.3.6.9"):
                status, _, body = render(s, vol)
                said.append((f"render {vol}", body))
                assert status == 404 and b"Outside" not in body, (vol, status, body[:300])
            status, _, body = render(s, "leak#1.2.3.6.9")
            assert b"outside the data directories" in body, body[:300]
            for vol in ("chest", "two#1.2.3.6.3", "two#Soft tissue"):
                status, _, body = render(s, vol)
                said.append((f"render {vol}", body))
                assert status == 200, f"{vol}: {status} {body[:300]}"
            status, _, body = render(s, "two")
            assert status == 404 and b"2 DICOM series" in body and b"Bone" in body, (status, body[:300])
            vols = {v["id"]: v for v in listing(s)["volumes"]}
            said.append(("GET /api/volumes", json.dumps(vols)))
            c = vols["chest"]
            assert c["value_unit"] == "HU" and c["modality"] == "CT" and c["dtype"] == "int16", c
            assert c["description"] == "Chest 2.0" and c["name"] == "chest (Chest 2.0)", c
            assert c["range"] == [-500, 577] and c["spacing"] == [0.5, 0.5, 2.0], c
            # A ZIP of the series: an upload; entry names with ../ reach nothing outside.
            z = zip_of(os.path.join(data, "chest"), lambda n: "../../" + n)
            status, _, body = upload(s, z, "name=chest.zip")
            said.append(("the upload", body))
            assert status == 201, f"{status} {body[:400]}"
            info = json.loads(body)
            assert info["value_unit"] == "HU" and info["dims"] == [8, 8, 6] and info["range"] == [-500, 577], info
            assert not any(n.startswith("IM") for n in os.listdir(os.path.dirname(up))), "a ZIP entry left its folder"
            status, _, body = render(s, info["id"])
            assert status == 200, body[:300]
            # Refused: a ZIP of no DICOM slices; one that says it decodes past the budget (4 MiB).
            plain = io.BytesIO()
            with zipfile.ZipFile(plain, "w") as zf:
                zf.writestr("notes.txt", b"not a slice")
            status, _, body = upload(s, plain.getvalue(), "name=notes.zip")
            assert status == 422 and b"no DICOM image slices" in body, (status, body[:300])
            big = io.BytesIO()
            with zipfile.ZipFile(big, "w", zipfile.ZIP_DEFLATED) as zf:
                zf.writestr("zeros", bytes(8 << 20))
            status, _, body = upload(s, big.getvalue(), "name=bomb.zip")
            assert status == 413 and b"decodes to more than" in body, (status, body[:300])
            left = [f for f in os.listdir(up) if not f.endswith(".upload.json") and f != ".incoming"]
            assert len(left) == 1, f"refused uploads left files: {left}"
            no_identifiers(said)
        no_identifiers([("the server's log", "".join(s.log))])


if __name__ == "__main__":
    run_tests([test_series_listed_rendered_uploaded_and_anonymous])
