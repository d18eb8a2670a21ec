"""Arrays larger than memory (or than the server's budget) sent chunk by chunk: a zarr or dask
array, a numpy memmap, anything with `.shape`, `.dtype` and slicing. Only one chunk is ever in
the client's memory; the server builds an OME-Zarr pyramid from the chunks when they are all
there (POST /api/uploads, docs/rest.md "Chunked uploads")."""
import json
import time
import urllib.parse

import numpy as np

from ._http import ServerError

_MAX_CHUNK_BYTES = 16 << 20  # the server's limit for one chunk
_AIM_CHUNK_BYTES = 8 << 20
_KINDS = {np.dtype(np.uint8): "uint8", np.dtype(np.int8): "int8", np.dtype(np.uint16): "uint16",
          np.dtype(np.int16): "int16", np.dtype(np.float32): "float32"}
_FLOAT32_MAX = float(np.finfo(np.float32).max)


class UploadInterrupted(Exception):
    """A chunked upload stopped before it was whole (the connection, the server, the script):
    `upload_id` resumes it (`Client.upload_chunked(array, resume=e.upload_id)`, the same array),
    `sent` of `chunks` arrived."""

    def __init__(self, upload_id, sent, chunks, cause):
        super().__init__(f"upload {upload_id} stopped after {sent} of {chunks} chunks ({cause}); resume it with "
                         f"upload_chunked(array, resume={upload_id!r})")
        self.upload_id, self.sent, self.chunks = upload_id, sent, chunks


def _server_dtype(dtype):
    dtype = np.dtype(dtype)
    if dtype.kind == "f":
        return np.dtype(np.float32)
    if dtype.newbyteorder("=") in _KINDS:
        return dtype.newbyteorder("=")
    raise ValueError(f"an array of {dtype} cannot be sent: uint8, int8, uint16, int16 or float32 (float64 as "
                     "float32)")


def _chunk_shape(array, bpv, chunk):
    """(z, y, x) of each chunk: the one asked, else the array's own (zarr .chunks, dask
    .chunksize) when within the limit, else about 8 MiB of whole rows."""
    shape = tuple(int(n) for n in array.shape)
    if chunk is None:
        own = getattr(array, "chunksize", None) or getattr(array, "chunks", None)
        if own is not None and len(own) == 3 and all(isinstance(c, (int, np.integer)) for c in own):
            chunk = tuple(int(c) for c in own)
    if chunk is None:
        x, y = min(shape[2], 512), min(shape[1], 512)
        chunk = (max(1, min(shape[0], _AIM_CHUNK_BYTES // (x * y * bpv))), y, x)
    chunk = tuple(max(1, min(int(c), n)) for c, n in zip(chunk, shape))
    if chunk[0] * chunk[1] * chunk[2] * bpv > _MAX_CHUNK_BYTES:
        raise ValueError(f"chunks of {chunk} hold more than the server's 16 MiB a chunk: give a smaller chunk=")
    return chunk


def _block(array, k, j, i, chunk, dtype):
    z, y, x = (a * c for a, c in zip((k, j, i), chunk))
    b = np.asarray(array[z:z + chunk[0], y:y + chunk[1], x:x + chunk[2]])  # only this block is read
    if b.dtype != dtype:
        if dtype == np.float32 and b.dtype.kind == "f":
            finite = b[np.isfinite(b)]
            if finite.size and float(np.abs(finite).max()) > _FLOAT32_MAX:
                raise ValueError(f"values past float32's range in the block at z, y, x = {z}, {y}, {x}: rescale "
                                 "them first (the server keeps floats as float32)")
        b = b.astype(dtype)
    return np.ascontiguousarray(b, dtype.newbyteorder("<")).tobytes()


def upload_chunked(http, array, spacing, name, origin, units, chunk, progress, resume, poll=0.25):
    if len(array.shape) != 3:
        raise ValueError(f"upload_chunked takes a 3-D array [z, y, x], not shape {tuple(array.shape)}")
    dtype = _server_dtype(array.dtype)
    shape = tuple(int(n) for n in array.shape)
    if resume:
        status = json.loads(http.request("GET", "/api/uploads/" + urllib.parse.quote(resume, safe=""))[2])
        if status["dims"] != list(shape[::-1]) or status["dtype"] != _KINDS[dtype]:
            raise ValueError(f"upload {resume} holds {status['dims']} {status['dtype']} (x, y, z), not this array")
        chunk = tuple(status["chunk"][::-1])
    else:
        chunk = _chunk_shape(array, dtype.itemsize, chunk)
        decl = {"dims": list(shape[::-1]), "dtype": _KINDS[dtype], "chunk": list(chunk[::-1])}
        for key, v in (("spacing", spacing), ("origin", origin)):
            if v is not None:
                decl[key] = [float(c) for c in v]
        if units is not None:
            decl["units"] = units
        if name is not None:
            decl["name"] = name
        status = json.loads(http.request("POST", "/api/uploads", json.dumps(decl).encode(),
                                         {"Content-Type": "application/json"})[2])
    uid, (gx, gy, gz) = status["id"], status["grid"]
    have = {f for a, b in status["received_runs"] for f in range(a, b)}
    total, sent = gx * gy * gz, len(have)
    try:
        for k in range(gz):
            for j in range(gy):
                for i in range(gx):
                    if i + gx * (j + gy * k) in have:
                        continue
                    http.request("PUT", f"/api/uploads/{uid}/chunks/{i}/{j}/{k}", _block(array, k, j, i, chunk, dtype),
                                 {"Content-Type": "application/octet-stream"})
                    sent += 1
                    if progress:
                        progress(sent, total, "sending")
        http.request("POST", f"/api/uploads/{uid}/finish")
    except ValueError:
        raise
    except ServerError as e:
        if e.status < 500 and e.status != 429:  # refused, not interrupted: the request is wrong
            raise
        raise UploadInterrupted(uid, sent, total, e) from e
    except Exception as e:
        raise UploadInterrupted(uid, sent, total, e) from e
    while True:  # the server builds the pyramid
        status = json.loads(http.request("GET", f"/api/uploads/{uid}")[2])
        if status["state"] == "done":
            if progress:
                progress(total, total, "done")
            return status["volume"]
        if status["state"] == "failed":
            raise RuntimeError(f"the server could not build upload {uid}: {status.get('error')}")
        if progress:
            progress(total, total, "building")
        time.sleep(poll)
