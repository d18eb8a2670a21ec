"""The peakcast REST API from Python: health, volumes, uploads, stills."""
import http.client
import json
import os
import select
import urllib.parse

import numpy as np

# The voxel types the server keeps (numpy dtype -> the server's name).
_DTYPES = {np.dtype(np.uint8): "uint8", np.dtype(np.int8): "int8", np.dtype(np.uint16): "uint16",
           np.dtype(np.int16): "int16", np.dtype(np.float32): "float32"}
_CHUNK = 1 << 20


class ServerError(Exception):
    """The server refused or failed a request: `status` (HTTP), `code` (proto/'s error codes) and the
    server's message."""

    def __init__(self, status, code, message):
        super().__init__(f"{status} {code}: {message}")
        self.status, self.code, self.message = status, code, message


class Client:
    """A peakcast server at `url` ("http://host:8080"), with its bearer token if it has one."""

    def __init__(self, url="http://localhost:8080", token=None, timeout=300.0):
        u = urllib.parse.urlsplit(url)
        if u.scheme not in ("http", "https") or not u.hostname:
            raise ValueError(f"not an http(s) URL: {url!r}")
        self._https = u.scheme == "https"
        self._host, self._port = u.hostname, u.port or (443 if self._https else 80)
        self._base = u.path.rstrip("/")
        self.token, self.timeout = token, timeout

    # -- the routes ------------------------------------------------------------------------------

    def health(self):
        """The server's health: status, backend, sessions, uploads' limits, ..."""
        return self._json("GET", "/api/health")

    def volumes(self):
        """Every volume the server holds: a list of dicts (id, name, dims, dtype, spacing, range,
        uploaded, ...)."""
        return self._json("GET", "/api/volumes")["volumes"]

    def volume(self, volume_id):
        """One volume's info, with its histogram."""
        return self._json("GET", "/api/volumes/" + urllib.parse.quote(volume_id, safe=""))

    def upload(self, array_or_path, spacing=(1.0, 1.0, 1.0), name=None, origin=None, units=None, axes=None):
        """Sends a volume; returns its id, usable as a scene's "volume".

        An array is indexed [z, y, x] (any memory order) and holds uint8, int8, uint16, int16 or
        float32 (float64 is sent as float32, which the server keeps; other types are refused);
        spacing and origin are in x, y, z order, in `units` (a unit of length: "um", "nm",
        "mm", "micrometer", ...; None: the server shows lengths in "units"). A 4D array is a
        time series indexed [t, z, y, x] (`axes="tzyx"`, the default for 4D; a scene's "time"
        picks the point); channel axes ("czyx", "tczyx") are refused until the server draws
        channels. A path is a file the server reads as one
        file: NRRD (data attached), MetaImage (.mha) or TIFF; its header gives spacing and origin."""
        if isinstance(array_or_path, (str, os.PathLike)):
            path = os.fspath(array_or_path)
            query = {"name": name or os.path.basename(path)}
            with open(path, "rb") as f:
                return self._upload(query, f, os.path.getsize(path))["id"]
        a = np.asarray(array_or_path)
        axes = axes or {3: "zyx", 4: "tzyx"}.get(a.ndim, "")
        if not isinstance(axes, str) or len(axes) != a.ndim or axes not in ("zyx", "tzyx"):
            if isinstance(axes, str) and "c" in axes and len(axes) == a.ndim:
                raise ValueError(f"axes {axes!r}: the server does not draw channels yet; upload one channel "
                                 f"(e.g. array[:, 0] for 'czyx' as 'zyx') at a time")
            raise ValueError(f"a volume is indexed [z, y, x] (axes 'zyx'), a time series [t, z, y, x] ('tzyx'); "
                             f"this array has shape {a.shape}" + (f" and axes {axes!r}" if axes else ""))
        times = a.shape[0] if axes == "tzyx" else 1
        if a.dtype.kind == "f" and a.dtype.itemsize == 8:
            a = a.astype(np.float32)  # the server keeps floats as float32: numpy's default float goes as one
        if a.dtype.newbyteorder("=") not in _DTYPES:
            raise ValueError(f"dtype {a.dtype} is not one the server keeps (uint8, int8, uint16, int16, float32): "
                             f"convert it first, e.g. array.astype(np.float32)")
        if any(n < 2 for n in a.shape[-3:]):
            raise ValueError(f"every dimension must be >= 2 to render (shape {a.shape})")
        # x fastest in memory, little-endian: the raw layout the server reads.
        a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
        query = {"dims": ",".join(str(n) for n in a.shape[-3:][::-1]), "dtype": _DTYPES[a.dtype.newbyteorder("=")],
                 "spacing": ",".join(repr(float(s)) for s in _three(spacing, "spacing")),
                 "endian": "little", "name": name or "array"}
        if times > 1:
            query["times"] = str(times)
        if units is not None:
            if not isinstance(units, str):
                raise ValueError(f"units must be a unit of length such as 'um' or 'mm', not {units!r}")
            query["units"] = units
        if origin is not None:
            query["origin"] = ",".join(repr(float(o)) for o in _three(origin, "origin"))
        return self._upload(query, memoryview(a).cast("B"), a.nbytes)["id"]

    def delete(self, volume_id):
        """Removes an uploaded volume (a volume from the server's data directories cannot be)."""
        self._json("DELETE", "/api/volumes/" + urllib.parse.quote(volume_id, safe=""))

    def render(self, scene):
        """Renders a scene (a dict, as scene files hold it; "volume" may be an id) and returns the
        image as a numpy uint8 array (height, width, 3), row 0 at the top."""
        status, headers, body = self._request("POST", "/api/render?format=rgb", json.dumps(scene).encode(),
                                              {"Content-Type": "application/json"})
        w, h = int(headers["x-image-width"]), int(headers["x-image-height"])
        return np.frombuffer(body, np.uint8).reshape(h, w, 3).copy()

    def render_png(self, scene, path):
        """Renders a scene and writes the PNG the server encodes to `path`."""
        _, _, body = self._request("POST", "/api/render?format=png", json.dumps(scene).encode(),
                                   {"Content-Type": "application/json"})
        with open(path, "wb") as f:
            f.write(body)

    # -- HTTP ------------------------------------------------------------------------------------

    def _connection(self):
        cls = http.client.HTTPSConnection if self._https else http.client.HTTPConnection
        return cls(self._host, self._port, timeout=self.timeout)

    def _headers(self, extra=None):
        h = dict(extra or {})
        if self.token:
            h["Authorization"] = "Bearer " + self.token
        return h

    def _json(self, method, path):
        return json.loads(self._request(method, path)[2])

    def _request(self, method, path, body=None, headers=None):
        conn = self._connection()
        try:
            conn.request(method, self._base + path, body=body, headers=self._headers(headers))
            r = conn.getresponse()
            return _checked(r.status, {k.lower(): v for k, v in r.getheaders()}, r.read())
        finally:
            conn.close()

    def _upload(self, query, body, length):
        """POST /api/volumes with Expect: 100-continue: a refusal (size, budget, rate, token)
        arrives before the body is sent, as with curl."""
        conn = self._connection()
        try:
            conn.putrequest("POST", self._base + "/api/volumes?" + urllib.parse.urlencode(query))
            for k, v in self._headers({"Content-Type": "application/octet-stream", "Content-Length": str(length),
                                       "Expect": "100-continue"}).items():
                conn.putheader(k, v)
            conn.endheaders()
            if select.select([conn.sock], [], [], 5.0)[0]:  # else a server that ignores Expect: send anyway
                status, answer = _read_interim(conn.sock)
                if status != 100:
                    return json.loads(_checked(status, {}, answer)[2])
            if isinstance(body, memoryview):
                for i in range(0, length, _CHUNK):
                    conn.sock.sendall(body[i:i + _CHUNK])
            else:
                while chunk := body.read(_CHUNK):
                    conn.sock.sendall(chunk)
            r = conn.getresponse()
            return json.loads(_checked(r.status, {}, r.read())[2])
        finally:
            conn.close()


def _read_interim(sock):
    """The server's answer to the headers alone: (100, b"") to go on, or a whole refusal (status,
    body), read off the socket directly (http.client would wait past a 100 for the final answer)."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("the server closed the connection before answering")
        data += chunk
    head, _, rest = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    if status == 100:
        return 100, b""
    length = next((int(l.split(":", 1)[1]) for l in lines[1:] if l.lower().startswith("content-length:")), None)
    while length is not None and len(rest) < length:
        chunk = sock.recv(65536)
        if not chunk:
            break
        rest += chunk
    return status, rest if length is None else rest[:length]


def _checked(status, headers, body):
    if status >= 400:
        try:
            j = json.loads(body)
            code, message = j.get("error", "error"), j.get("message", "")
        except ValueError:
            code, message = "error", body[:500].decode("utf-8", "replace")
        raise ServerError(status, code, message)
    return status, headers, body


def _three(v, what):
    v = tuple(v)
    if len(v) != 3:
        raise ValueError(f"{what} is 3 numbers in x, y, z order")
    return v
