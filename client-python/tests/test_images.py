"""More than RGB: a still with alpha and no background (?format=rgba) lays over its background
back to the RGB still; a depth image (?format=depth) holds, pixel for pixel, the probe's distance."""
import json
import urllib.request

import numpy as np
import pytest

from conftest import blobs
import peakcast

# A light background: a still whose background stayed in its colours would be far off when laid
# over it again.
SCENE = {"image": {"width": 64, "height": 48}, "background": [0.9, 0.8, 0.7],
         "camera": {"eye": [60, 50, 70], "center": [13.5, 11.5, 9.5], "up": [0, 1, 0]}}


@pytest.mark.parametrize("render", [{}, {"classification": "peaks", "shading": True}])
def test_rgba_laid_over_its_background_is_the_rgb_still(server, render):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    try:
        scene = dict(SCENE, volume=vid, render=render)
        rgb = np.asarray(c.render(scene), np.float64)
        rgba = c.render_rgba(scene)
        assert rgba.shape == (48, 64, 4) and rgba.dtype == np.uint8 and rgba.tf_source == "auto", rgba.shape
        a = np.asarray(rgba[..., 3:], np.float64) / 255
        over = np.asarray(rgba[..., :3], np.float64) * a + (1 - a) * 255 * np.array(SCENE["background"])
        worst = np.abs(over - rgb).max()
        print(f"  {render or 'default'}: rgba over its background against rgb, max abs {worst:.2f}/255; "
              f"{(a == 0).mean():.0%} transparent")
        assert worst <= 2, worst
        assert rgba[0, 0, 3] == 0 and (a == 0).mean() > 0.1 and (a > 0.5).mean() > 0.05  # misses see through
    finally:
        c.delete(vid)


def test_the_float_image_is_the_still_before_rounding(server):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    try:
        scene = dict(SCENE, volume=vid, render={"classification": "peaks", "shading": True})
        rgb = np.asarray(c.render(scene), np.float64)
        f = c.render_float(scene)
        rgba = c.render_rgba(scene)
        assert f.shape == (48, 64, 4) and f.dtype == np.float32 and f.tf_source == "auto", f.shape
        # The 8-bit still is the float image rounded; its alpha is the RGBA still's.
        assert np.abs(np.clip(f[..., :3], 0, 1) * 255 - rgb).max() <= 0.5 + 1e-3
        assert np.abs(np.clip(f[..., 3], 0, 1) * 255 - rgba[..., 3]).max() <= 0.5 + 1e-3
        assert f[0, 0, 3] == 0 and np.allclose(f[0, 0, :3], SCENE["background"])  # a miss: the background
        assert len(np.unique(f[..., 0])) > len(np.unique(rgb[..., 0]))  # finer than 8 bits
    finally:
        c.delete(vid)


def test_depth_is_the_probe_distance_of_every_pixel(server):
    c = peakcast.Client(server.url)
    vid = c.upload(blobs())
    try:
        scene = dict(SCENE, volume=vid, render={"classification": "peaks"})
        depth = c.render_depth(scene)
        assert depth.shape == (48, 64) and depth.dtype == np.float32, (depth.shape, depth.dtype)
        assert np.isnan(depth[0, 0]) and np.isfinite(depth).mean() > 0.05, np.isfinite(depth).mean()
        for x, y in [(0, 0), (32, 24), (20, 30), (40, 15), (63, 47)]:
            req = urllib.request.Request(server.url + "/api/probe", method="POST",
                                         data=json.dumps(dict(scene, pixel=[x, y], pick="half")).encode())
            probe = json.loads(urllib.request.urlopen(req).read())
            if probe["hit"]:
                assert depth[y, x] == pytest.approx(probe["distance"], rel=1e-6), (x, y, depth[y, x], probe)
            else:
                assert np.isnan(depth[y, x]), (x, y, depth[y, x])
        # Raw bytes, as a script without the client reads them.
        req = urllib.request.Request(server.url + "/api/render?format=depth", method="POST",
                                     data=json.dumps(scene).encode())
        with urllib.request.urlopen(req) as r:
            w, h = int(r.headers["X-Width"]), int(r.headers["X-Height"])
            raw = np.frombuffer(r.read(), "<f4").reshape(h, w)
        assert np.array_equal(raw, depth, equal_nan=True)
        with pytest.raises(peakcast.ServerError) as e:
            c.render_depth(dict(scene, volume="no-such.nrrd"))
        assert e.value.status == 404
    finally:
        c.delete(vid)


def test_an_unknown_format_names_the_known_ones(server):
    req = urllib.request.Request(server.url + "/api/render?format=tiff", method="POST",
                                 data=json.dumps({"volume": "heptane_151.nrrd"}).encode())
    with pytest.raises(urllib.error.HTTPError) as e:
        urllib.request.urlopen(req)
    assert e.value.code == 400 and b"png, jpeg, rgb, rgba, float or depth" in e.value.read()


def test_the_png_reader_matches_pil(server, tmp_path):
    """The client's PNG reader (standard library only) against PIL on the server's PNGs and on
    PIL's own, whose filters vary per row (sub, up, average, paeth)."""
    from PIL import Image as PIL
    from peakcast._png import decode_png
    c = peakcast.Client(server.url)
    c.render_png({"volume": "heptane_151.nrrd", "image": {"width": 80, "height": 60}}, tmp_path / "s.png")
    rng = np.random.default_rng(1)
    smooth = (np.add.outer(np.arange(40), np.arange(50))[..., None] * [1, 2, 3] % 256).astype(np.uint8)
    noisy = np.dstack([smooth, rng.integers(0, 256, (40, 50, 1), dtype=np.uint8)])
    PIL.fromarray(noisy, "RGBA").save(tmp_path / "n.png")
    for path in (tmp_path / "s.png", tmp_path / "n.png"):
        mine = decode_png(path.read_bytes())
        theirs = np.asarray(PIL.open(path))
        assert mine.shape == theirs.shape and np.array_equal(mine, theirs), path.name
    with pytest.raises(ValueError, match="not a PNG"):
        decode_png(b"GIF89a")


def test_a_tf_from_a_named_colour_map_and_its_limits(server):
    """colormap_tf(name, limits, opacity): the server's stops spread over the limits with an
    opacity ramp; the derived TF's colours are viridis', and the viewer's maps are the server's."""
    import pathlib
    c = peakcast.Client(server.url)
    maps = c.colormaps()
    assert set(maps) == {"viridis", "magma", "coolwarm", "grey"} and maps["grey"].tolist() == [[0, 0, 0], [1, 1, 1]]
    tf = c.colormap_tf("magma", limits=(1000, 5000), opacity=(0, 0.5))
    pts = np.asarray(tf["points"])
    assert len(pts) == len(maps["magma"]) and pts[0, 0] == 1000 and pts[-1, 0] == 5000, pts
    assert np.allclose(pts[:, 1:4], maps["magma"]) and pts[0, 4] == 0 and pts[-1, 4] == 0.5, pts
    vid = c.upload(blobs())
    try:
        lo, hi = c.volume(vid)["range"]
        narrow = c.render(dict(SCENE, volume=vid, tf=c.colormap_tf("magma", (lo + 0.5 * (hi - lo), hi))))
        wide = c.render(dict(SCENE, volume=vid, tf=c.colormap_tf("magma", (lo, hi))))
        assert np.abs(np.asarray(narrow, int) - wide).mean() > 1  # the limits are drawn
        derived = np.asarray(c.tf(dict(SCENE, volume=vid))["points"])[:, 1:4]
        t = np.linspace(0, 1, len(maps["viridis"]))
        on_viridis = [min(np.abs(np.array([np.interp(u, t, maps["viridis"][:, k]) for k in range(3)]) - p).max()
                          for u in np.linspace(0, 1, 1001)) for p in derived]
        assert max(on_viridis) < 0.01, on_viridis  # the automatic TF's colours lie on viridis
    finally:
        c.delete(vid)
    with pytest.raises(ValueError, match="no colour map 'jet'"):
        c.colormap_tf("jet", (0, 1))
    with pytest.raises(ValueError, match="limits"):
        c.colormap_tf("grey", (1, 1))
    # One source of stops: the viewer (client-web) asks the server for them and holds none itself
    # (tests/browser/viewer.test.mjs checks its presets against GET /api/colormaps).
    js = (pathlib.Path(__file__).resolve().parents[2] / "client-web/src/tf-model.js").read_text()
    assert "/api/colormaps" in js and "253, 231, 37" not in js and "0.9921" not in js
