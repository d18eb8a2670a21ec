"""peakcast: a Python client for the peakcast volume render server.

    import numpy as np, peakcast
    client = peakcast.Client("http://localhost:8080")
    vid = client.upload(np.random.rand(64, 96, 128).astype(np.float32), spacing=(1, 1, 2))
    image = client.render({"volume": vid, "image": {"width": 512, "height": 512}})  # (512, 512, 3) uint8
    image.warnings, image.tf_source, image.info.render_ms  # what the server said about it

Arrays are indexed [z, y, x] (the numpy imaging convention of tifffile, zarr and napari); spacing
and origin are given in x, y, z order, as in scene files. Only the standard library and numpy.
"""
from .chunked import UploadInterrupted
from .client import Client, ServerError
from .image import Image, RenderInfo
from .movie import MovieInfo

__all__ = ["Client", "ServerError", "Image", "RenderInfo", "MovieInfo", "UploadInterrupted"]
__version__ = "0.1.0"
