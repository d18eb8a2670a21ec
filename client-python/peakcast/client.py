"""The peakcast REST API from Python: health, volumes, uploads, stills."""
import json
import os
import urllib.parse

import numpy as np

from ._http import ServerError, Transport  # noqa: F401 (ServerError: peakcast.ServerError)
from ._png import decode_png
from .image import Image, RenderInfo
from .chunked import upload_chunked
from .movie import MovieInfo, movie_body, rgb_frames

# The voxel types the server keeps (numpy dtype -> the server's name).
_DTYPES = {np.dtype(np.uint8): "uint8", np.dtype(np.int8): "int8", np.dtype(np.uint16): "uint16",
           np.dtype(np.int16): "int16", np.dtype(np.float32): "float32"}
_FLOAT32_MAX = float(np.finfo(np.float32).max)


class Client:
    """A peakcast server at `url` ("http://host:8080"), with its bearer token if it has one.

    Thread-safe: each thread keeps one connection alive across calls. A refusal that says when to
    come back (503 queue_full or uploads_busy, 429 rate_limited, with Retry-After) is waited out up
    to `retries` times, at most `max_retry_wait` seconds each; `retries=0` raises it at once.
    `with Client(...) as c:` closes the connections at the end."""

    def __init__(self, url="http://localhost:8080", token=None, timeout=300.0, retries=3, max_retry_wait=30.0):
        self._http = Transport(url, token, timeout, retries, max_retry_wait)

    token = property(lambda self: self._http.token)
    retries = property(lambda self: self._http.retries)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        """Closes the kept connections (a later call opens a new one)."""
        self._http.close()

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

    def upload(self, array_or_path, spacing=None, name=None, origin=None, units=None, axes=None):
        """Sends a volume; returns its id, usable as a scene's "volume".

        An array is indexed [z, y, x] (any memory order) and holds uint8, int8, uint16, int16 or
        float32 (float16 and float64 are sent as float32, which the server keeps, float64 refused
        when a value does not fit in float32; other types are refused); spacing (default 1, 1, 1) and origin are in
        x, y, z order, in `units` (a unit of length: "um", "nm",
        "mm", "micrometer", ...; None: the server shows lengths in "units"). A 4D array is a
        time series indexed [t, z, y, x] (`axes="tzyx"`, the default for 4D; a scene's "time"
        picks the point); channel axes ("czyx", "tczyx") are refused until the server draws
        channels. A path is a file the server reads as one
        file: NRRD (data attached), MetaImage (.mha) or TIFF; its header gives spacing, origin and
        units, and giving them here is refused (they would not be used)."""
        if isinstance(array_or_path, (str, os.PathLike)):
            path = os.fspath(array_or_path)
            given = [k for k, v in (("spacing", spacing), ("origin", origin), ("units", units), ("axes", axes))
                     if v is not None]
            if given:
                raise ValueError(f"{', '.join(given)}: a file's own header gives them, so they would not be used; "
                                 f"fix the header, or read the file into an array and upload that")
            query = {"name": name or os.path.basename(path)}
            with open(path, "rb") as f:
                return self._upload(query, f, os.path.getsize(path), rewind=lambda: f.seek(0))["id"]
        a = np.asarray(array_or_path)
        axes = axes or {3: "zyx", 4: "tzyx"}.get(a.ndim, "")
        if not isinstance(axes, str) or len(axes) != a.ndim or axes not in ("zyx", "tzyx"):
            if isinstance(axes, str) and "c" in axes and len(axes) == a.ndim:
                raise ValueError(f"axes {axes!r}: the server does not draw channels yet; upload one channel "
                                 f"(e.g. array[:, 0] for 'czyx' as 'zyx') at a time")
            raise ValueError(f"a volume is indexed [z, y, x] (axes 'zyx'), a time series [t, z, y, x] ('tzyx'); "
                             f"this array has shape {a.shape}" + (f" and axes {axes!r}" if axes else ""))
        times = a.shape[0] if axes == "tzyx" else 1
        if a.dtype.kind == "f" and a.dtype.itemsize != 4:
            a = _as_float32(a)  # the server keeps floats as float32: numpy's default float goes as one
        if a.dtype.newbyteorder("=") not in _DTYPES:
            raise ValueError(f"dtype {a.dtype} is not one the server keeps (uint8, int8, uint16, int16, float32): "
                             f"convert it first, e.g. array.astype(np.float32)")
        if any(n < 2 for n in a.shape[-3:]):
            raise ValueError(f"every dimension must be >= 2 to render (shape {a.shape})")
        # x fastest in memory, little-endian: the raw layout the server reads.
        a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
        query = {"dims": ",".join(str(n) for n in a.shape[-3:][::-1]), "dtype": _DTYPES[a.dtype.newbyteorder("=")],
                 "spacing": ",".join(repr(float(s)) for s in _three((1.0, 1.0, 1.0) if spacing is None else spacing,
                                                                    "spacing")),
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

    def upload_chunked(self, array, spacing=None, name=None, origin=None, units=None, chunk=None, progress=None,
                       resume=None):
        """Sends an array larger than memory, or than the server's budget, chunk by chunk; returns
        its volume id once the server has built its pyramid. `array` is anything indexed [z, y, x]
        with `.shape`, `.dtype` and slicing (a zarr or dask array, a numpy memmap): one chunk at a
        time is read from it. `chunk` (z, y, x): the array's own chunks by default, at most 16 MiB.
        `progress(done, total, stage)` hears each chunk ("sending"), the build ("building") and the
        end ("done"). An interruption raises peakcast.UploadInterrupted; `resume=e.upload_id` with
        the same array sends only the chunks that did not arrive. The volume opens at the finest
        level of its pyramid that the server's memory budget holds."""
        return upload_chunked(self._http, array, spacing, name, origin, units, chunk, progress, resume)

    def delete(self, volume_id):
        """Removes an uploaded volume (a volume from the server's data directories cannot be)."""
        self._json("DELETE", "/api/volumes/" + urllib.parse.quote(volume_id, safe=""))

    def render(self, scene):
        """Renders a scene (a dict, as scene files hold it; "volume" may be an id; numpy numbers and
        arrays may stand for numbers and lists) and returns an Image: a numpy uint8 array (height,
        width, 3), row 0 at the top, whose `info` keeps what the server said (`warnings`,
        `tf_source`, `level`, `bricks`, `time`, timings)."""
        _, headers, body = self._render(scene, "rgb")
        w, h = int(headers["x-image-width"][0]), int(headers["x-image-height"][0])
        return Image(np.frombuffer(body, np.uint8).reshape(h, w, 3).copy(), RenderInfo(headers))

    def render_rgba(self, scene):
        """The still with alpha and no background: an Image (height, width, 4) uint8, straight
        (not premultiplied) alpha, 0 where nothing was hit: ready to lay over another picture."""
        _, headers, body = self._render(scene, "rgba")
        return Image(decode_png(body), RenderInfo(headers))

    def render_float(self, scene):
        """The still as the renderer drew it, before 8-bit rounding: an Image (height, width, 4)
        float32, rgb the colour over the scene's background in [0, 1] (sRGB values, as the PNG's
        / 255), a the ray's opacity."""
        _, headers, body = self._render(scene, "float")
        w, h = int(headers["x-width"][0]), int(headers["x-height"][0])
        return Image(np.frombuffer(body, "<f4").reshape(h, w, 4).astype(np.float32), RenderInfo(headers))

    def render_depth(self, scene):
        """The distance from the eye (the image plane for orthographic views) to where each pixel's
        ray first passes half opacity, the probe's rule: an Image (height, width) float32 in world
        units, NaN where nothing was hit. Drawn by the server's reference ray: seconds for 512²."""
        _, headers, body = self._render(scene, "depth")
        w, h = int(headers["x-width"][0]), int(headers["x-height"][0])
        return Image(np.frombuffer(body, "<f4").reshape(h, w).astype(np.float32), RenderInfo(headers))

    def colormaps(self):
        """The server's named colour maps: {name: (n, 3) float array of sRGB stops in [0, 1],
        evenly spaced}."""
        maps = self._json("GET", "/api/colormaps")["colormaps"]
        return {name: np.asarray(stops, np.float64) for name, stops in maps.items()}

    def colormap_tf(self, name, limits, opacity=(0.0, 0.6)):
        """A TF from a named colour map (matplotlib's way: `name`, contrast `limits=(vmin, vmax)`
        in data values) with an opacity ramp from opacity[0] at vmin to opacity[1] at vmax; values
        below vmin take the first point, above vmax the last. A dict for a scene's "tf"."""
        maps = self.colormaps()
        if name not in maps:
            raise ValueError(f"no colour map {name!r}: the server has {', '.join(sorted(maps))}")
        lo, hi = (float(v) for v in limits)
        a0, a1 = (float(v) for v in opacity)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ValueError(f"limits must be two finite numbers, the first below the second, not {limits!r}")
        if not (0 <= a0 <= 1 and 0 <= a1 <= 1):
            raise ValueError(f"opacity must be two numbers in [0, 1], not {opacity!r}")
        stops = maps[name]
        t = np.linspace(0.0, 1.0, len(stops))
        return {"points": [[lo + f * (hi - lo), *map(float, c), a0 + f * (a1 - a0)] for f, c in zip(t, stops)]}

    def tf(self, scene):
        """The TF a scene is drawn with, as a dict to edit and put back into a scene:
        {"points": [[value, r, g, b, a], ...], "opacity_unit": u}. A scene without "tf" gets the one
        the server derives from the volume's histogram (with an opacity peak when its
        render.classification is "peaks"); `.last_tf_source` says "auto" or "scene"."""
        _, _, body = self._http.request("POST", "/api/tf", scene_json(scene), {"Content-Type": "application/json"})
        answer = json.loads(body)
        self.last_tf_source = answer["tf_source"]
        return answer["tf"]

    def movie(self, scene, path, orbit=None, keys=None, frames=60, fps=30, format=None, quality=None):
        """Renders a movie on the server and writes it to `path` as it streams in; returns a
        MovieInfo. The camera follows `orbit` ({"axis": [x, y, z], "degrees": d}: about the focal
        point; axis default the view up, degrees 360) or `keys` (a list of {"camera", "tf", "time"},
        each optional, spread evenly over the frames and interpolated). `format` "mp4" (H.264),
        "webm" (VP9), "png-zip" (lossless frames) or "rgb" (the frames' bytes one after the
        other); default from the path's suffix (.webm, .zip, .rgb), else mp4. `quality` 10..100
        as a JPEG's (default 90)."""
        if format is None:
            suffix = os.path.splitext(str(path))[1].lower()
            format = {".webm": "webm", ".zip": "png-zip", ".rgb": "rgb"}.get(suffix, "mp4")
        headers, pieces = self._movie(scene, orbit, keys, frames, fps, format, quality)
        size = 0
        with open(path, "wb") as f:
            for piece in pieces:
                f.write(piece)
                size += len(piece)
        return MovieInfo(headers, size)

    def movie_frames(self, scene, orbit=None, keys=None, frames=60, quality=None):
        """The frames of a movie (as `movie` makes it) as Images (height, width, 3) uint8, each
        yielded as soon as the server has drawn it, exactly the stills of their cameras: a camera
        path without a loop in Python. Stop iterating (or close the iterator) to end the movie."""
        headers, pieces = self._movie(scene, orbit, keys, frames, 30, "rgb", quality)
        return rgb_frames(headers, pieces)

    def _movie(self, scene, orbit, keys, frames, fps, fmt, quality):
        body = scene_json(movie_body(scene, orbit, keys, frames, fps, fmt, quality))
        return self._http.stream("POST", "/api/movie", body, {"Content-Type": "application/json"})

    def render_png(self, scene, path):
        """Renders a scene and writes the PNG the server encodes to `path`; returns its RenderInfo."""
        _, headers, body = self._render(scene, "png")
        with open(path, "wb") as f:
            f.write(body)
        return RenderInfo(headers)

    def _render(self, scene, fmt):
        return self._http.request("POST", "/api/render?format=" + fmt, scene_json(scene),
                                  {"Content-Type": "application/json"})

    # -- HTTP ------------------------------------------------------------------------------------

    def _json(self, method, path):
        return json.loads(self._http.request(method, path)[2])

    def _upload(self, query, body, length, rewind=lambda: None):
        return self._http.upload("/api/volumes?" + urllib.parse.urlencode(query), body, length, rewind)


def scene_json(scene):
    """The scene as JSON bytes; numpy numbers and arrays become JSON numbers and lists."""
    try:
        return json.dumps(scene, default=_plain, allow_nan=False).encode()
    except ValueError as e:
        raise ValueError(f"a scene holds numbers JSON has (no NaN or infinity): {e}") from None


def _plain(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"a scene holds numbers, strings, lists and dicts, not {type(o).__name__} ({o!r})")


def _as_float32(a):
    """float64 (or wider) as float32, refused when a finite value does not fit (it would become
    infinity, which the server replaces, and the data is lost)."""
    finite = a[np.isfinite(a)]
    if finite.size:
        lo, hi = float(finite.min()), float(finite.max())
        if max(-lo, hi) > _FLOAT32_MAX:
            raise ValueError(f"values {lo:g}..{hi:g} do not fit in float32 (at most {_FLOAT32_MAX:.4g}), the type "
                             f"the server keeps floats as: rescale them first (e.g. array / {max(-lo, hi):.0e})")
    return a.astype(np.float32)


def _three(v, what):
    v = tuple(v)
    if len(v) != 3:
        raise ValueError(f"{what} is 3 numbers in x, y, z order")
    return v
