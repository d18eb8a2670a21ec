"""Movies made on the server (POST /api/movie): a scene and a camera path, rendered frame after
frame and streamed back as the file is made."""
import numpy as np

from .image import Image, RenderInfo


class MovieInfo:
    """What the server said about a movie: `frames`, `fps`, `format` ("mp4", "webm",
    "png-zip", "rgb"), `encoder` (libx264, libvpx-vp9, png, rgb), `width`, `height`, `level`, `tf_source`,
    `warnings`, `bytes` (the file's size) and `headers` (every header, lower-cased)."""

    __slots__ = ("frames", "fps", "format", "encoder", "width", "height", "level", "tf_source", "warnings", "bytes",
                 "headers")

    def __init__(self, headers, size=0):
        one = lambda name, kind=str: kind(headers[name][-1]) if headers.get(name) else None  # noqa: E731
        self.headers, self.bytes = headers, size
        self.frames, self.fps, self.format = one("x-frames", int), one("x-fps", int), one("x-format")
        self.encoder, self.width, self.height = one("x-encoder"), one("x-width", int), one("x-height", int)
        self.level, self.tf_source = one("x-level", int), one("x-tf-source")
        self.warnings = list(headers.get("x-warning", []))

    def __repr__(self):
        return "MovieInfo(" + ", ".join(f"{k}={getattr(self, k)!r}" for k in self.__slots__ if k != "headers") + ")"


def movie_body(scene, orbit, keys, frames, fps, fmt, quality):
    """The request: the scene plus "path" (an orbit: {"axis": [x, y, z], "degrees": d}, or a
    list of key frames {"camera": ..., "tf": ..., "time": ...}), "frames", "fps", "format"."""
    if (orbit is None) == (keys is None):
        raise ValueError("give a movie either orbit={'axis': [x, y, z], 'degrees': d} or keys=[...], not both")
    body = dict(scene)
    body["path"] = {"orbit": dict(orbit)} if orbit is not None else {"keys": list(keys)}
    body.update({"frames": frames, "fps": fps, "format": fmt})
    if quality is not None:
        body["quality"] = quality
    return body


class _Reader:
    """Exact reads from an iterator of byte strings; None at the end."""

    def __init__(self, chunks):
        self._chunks, self._buf = chunks, bytearray()

    def read(self, n):
        while len(self._buf) < n:
            piece = next(self._chunks, None)
            if piece is None:
                if self._buf:
                    raise ConnectionError(f"the movie ended {n - len(self._buf)} bytes short of a frame")
                return None
            self._buf += piece
        out = bytes(self._buf[:n])
        del self._buf[:n]
        return out


def rgb_frames(headers, chunks):
    """The frames of a movie streamed as "rgb" (each width x height x 3 bytes, rows from the top)
    as Images, each as soon as its bytes arrived."""
    info = RenderInfo(headers)
    w, h = int(headers["x-width"][-1]), int(headers["x-height"][-1])
    r = _Reader(chunks)
    try:
        while (frame := r.read(w * h * 3)) is not None:
            yield Image(np.frombuffer(frame, np.uint8).reshape(h, w, 3), info)
    finally:
        chunks.close()  # a script that stops early closes the connection: the server ends the movie
