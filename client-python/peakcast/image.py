"""A rendered still: a numpy array that keeps what the server said about it."""
import numpy as np


class RenderInfo:
    """What the server said about one still (its X- headers, read into Python values).

    warnings   list of str: what the scene asked for that it did not get (e.g. peaks with no
               opacity peak); empty when none
    tf_source  "scene" (the scene's TF) or "auto" (derived from the volume's histogram)
    level      the pyramid level drawn (0: the finest; 0 for every volume that is not a pyramid)
    bricks     how many bricks a still drawn by bricks took (out of core), or None
    time       the time point drawn
    variant    the renderer's variant (classification, sampling, ...)
    render_ms, encode_ms, wait_ms, samples_per_ray, bands: the server's timings and counts
    headers    every header of the answer, lower-cased names, a list of values each
    """

    __slots__ = ("warnings", "tf_source", "level", "bricks", "time", "variant", "render_ms", "encode_ms", "wait_ms",
                 "samples_per_ray", "bands", "headers")

    def __init__(self, headers):
        self.headers = headers

        def one(name, kind=str, default=None):
            v = headers.get(name)
            return kind(v[-1]) if v else default

        self.warnings = list(headers.get("x-warning", []))
        self.tf_source = one("x-tf-source")
        self.level = one("x-level", int, 0)
        self.bricks = one("x-bricks", int)
        self.time = one("x-time", int, 0)
        self.variant = one("x-variant")
        self.render_ms = one("x-render-ms", float)
        self.encode_ms = one("x-encode-ms", float)
        self.wait_ms = one("x-wait-ms", float)
        self.samples_per_ray = one("x-samples-per-ray", float)
        self.bands = one("x-bands", int)

    def as_dict(self):
        return {k: getattr(self, k) for k in self.__slots__ if k != "headers"}

    def __repr__(self):
        return "RenderInfo(" + ", ".join(f"{k}={v!r}" for k, v in self.as_dict().items()) + ")"


class Image(np.ndarray):
    """A still as numpy holds images, (height, width, channels), row 0 at the top, with `info`
    (a RenderInfo) and its main fields as attributes: `warnings`, `tf_source`, `level`, `bricks`,
    `time`. Slices and views keep `info`; `np.asarray(image)` is the plain array."""

    def __new__(cls, array, info):
        obj = np.asarray(array).view(cls)
        obj.info = info
        return obj

    def __array_finalize__(self, obj):
        self.info = getattr(obj, "info", None)

    def __reduce__(self):  # pickles (multiprocessing) as a plain array: info is the server's word on one call
        return np.asarray(self).__reduce__()

    warnings = property(lambda self: self.info.warnings if self.info else [])
    tf_source = property(lambda self: self.info.tf_source if self.info else None)
    level = property(lambda self: self.info.level if self.info else None)
    bricks = property(lambda self: self.info.bricks if self.info else None)
    time = property(lambda self: self.info.time if self.info else None)
