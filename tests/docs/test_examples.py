#!/usr/bin/env python3
"""Every example in README.md and docs/ that renders shows a picture worth looking at: the
README's curl and Python stills (peak finding), the docs' REST still without a TF or camera (the
derived TF and three-quarter view), the documented scene file, and the first picture of every
sample volume. Each is held to a minimum contrast (the standard deviation of luminance); a faint
haze of the same volume is shown to fall below it, so the bound can fail. Peak finding
with a TF that has no peak renders and warns, in the REST headers and in `render --stats`."""
import io, json, os, pathlib, re, subprocess, sys, tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests/net"))
from harness import DATA, PEAKCAST, Server, http  # noqa: E402
from PIL import Image, ImageStat  # noqa: E402

# The standard deviation of luminance over the picture (0..1). Measured on this checkout: the
# examples 0.082-0.110, the sample volumes' first pictures 0.105-0.212, a faint haze well below.
MIN_CONTRAST = 0.06


def contrast(png_bytes):
    img = Image.open(io.BytesIO(png_bytes)).convert("L")
    return ImageStat.Stat(img).stddev[0] / 255.0


def fenced(text, lang):
    return re.findall(rf"```{lang}\n(.*?)```", text, re.S)


def curl_render_bodies(text):
    """(query, body) of every `curl ... /api/render ... -d '...'` in the text's sh blocks."""
    out = []
    for block in fenced(text, "sh"):
        joined = re.sub(r"\\\n\s*", " ", block)
        for m in re.finditer(r"curl[^\n]*?/api/render(\?[^'\s]*)?'?[^\n]*?-d '(.*?)'", joined, re.S):
            out.append((m.group(1) or "", json.loads(m.group(2))))
    return out


def post(server, query, body):
    status, headers, data = http(server, "/api/render" + query, "POST", json.dumps(body).encode(),
                                 {"Content-Type": "application/json"})
    assert status == 200, (status, data[:300])
    return headers, data


def test_readme_curl_still_shows_peaks():
    bodies = curl_render_bodies((ROOT / "README.md").read_text())
    assert bodies, "the README has no curl still"
    with Server() as s:
        for query, body in bodies:
            assert body["render"]["classification"] == "peaks", body
            headers, data = post(s, query, body)
            assert "X-Warning" not in headers, headers
            assert headers["X-TF-Source"] == "scene"
            assert "peaks" in headers["X-Variant"], headers["X-Variant"]
            c = contrast(data)
            print(f"README curl still: contrast {c:.3f}")
            assert c >= MIN_CONTRAST, c


def test_readme_python_example_runs_and_shows_peaks():
    """The README's Python block, as written, against a live server (its URL swapped in), on a
    stack.npy of a sample volume; the image it makes is held to the bound."""
    blocks = [b for b in fenced((ROOT / "README.md").read_text(), "python") if "peakcast.Client" in b]
    assert blocks, "the README has no Python example"
    import numpy as np
    with tempfile.TemporaryDirectory() as tmp, Server("--upload-dir", str(pathlib.Path(tmp) / "uploads")) as s:
        # A real volume as the script's own array: heptane's voxels, indexed [z, y, x].
        np.save(pathlib.Path(tmp) / "stack.npy", heptane_array())
        for code in blocks:
            code = code.replace("http://localhost:8080", s.base) + "\nnp.save('image.npy', image)\n"
            env = dict(os.environ, PYTHONPATH=str(ROOT / "client-python"))
            subprocess.run([sys.executable, "-c", code], cwd=tmp, check=True, timeout=300, env=env)
            image = np.load(pathlib.Path(tmp) / "image.npy")
            assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3, image.shape
            buf = io.BytesIO()
            Image.fromarray(image).save(buf, format="PNG")
            c = contrast(buf.getvalue())
            print(f"README Python example: {image.shape}, contrast {c:.3f}")
            assert c >= MIN_CONTRAST, c


def heptane_array():
    """The heptane sample's voxels as a numpy array [z, y, x], read by `peakcast convert` to raw."""
    import numpy as np
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "h.raw"
        subprocess.run([PEAKCAST, "convert", DATA / "heptane_151.nrrd", out], check=True, capture_output=True)
        head = json.loads((pathlib.Path(tmp) / "h.raw.json").read_text()) if (pathlib.Path(tmp) / "h.raw.json").exists() \
            else json.loads((pathlib.Path(tmp) / "h.json").read_text())
        nx, ny, nz = head["dims"]
        return np.fromfile(out, np.uint8).reshape(nz, ny, nx)


def test_docs_rest_still_without_tf_or_camera():
    bodies = curl_render_bodies((ROOT / "docs/rest.md").read_text())
    assert bodies, "docs/rest.md has no curl still"
    with Server() as s:
        for query, body in bodies:
            headers, data = post(s, query, body)
            if "tf" not in body:
                assert headers["X-TF-Source"] == "auto", headers
            c = contrast(data)
            print(f"docs/rest.md still {query}: contrast {c:.3f}")
            assert c >= MIN_CONTRAST, c


def render(scene, tmp, name):
    path = pathlib.Path(tmp) / f"{name}.json"
    path.write_text(json.dumps(scene))
    out, stats = pathlib.Path(tmp) / f"{name}.png", pathlib.Path(tmp) / f"{name}.stats.json"
    r = subprocess.run([PEAKCAST, "render", path, "-o", out, "--stats", stats], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    return out.read_bytes(), json.loads(stats.read_text()), r.stderr


def test_documented_scene_file_shows_peaks():
    blocks = [json.loads(b) for b in fenced((ROOT / "docs/scenes.md").read_text(), "json") if b.lstrip().startswith("{")]
    demo = json.loads((ROOT / "scripts/demo/heptane.json").read_text())
    assert demo in blocks, "docs/scenes.md shows scripts/demo/heptane.json"
    demo["volume"] = str((ROOT / "scripts/demo" / demo["volume"]).resolve())
    with tempfile.TemporaryDirectory() as tmp:
        data, stats, _ = render(demo, tmp, "demo")
        assert stats["warnings"] == [] and "peaks" in stats["variant"], stats
        c = contrast(data)
        print(f"docs/scenes.md scene: contrast {c:.3f}")
        assert c >= MIN_CONTRAST, c


SAMPLES = ["heptane_151.nrrd", "HeadMRVolume.mhd", "nucleon.nhdr", "headsq/quarter.nhdr"]


def test_first_picture_of_every_sample_volume():
    with tempfile.TemporaryDirectory() as tmp:
        for i, name in enumerate(SAMPLES):
            for classification in ("post", "peaks"):
                scene = {"volume": str(DATA / name), "image": {"width": 256, "height": 256},
                         "render": {"classification": classification, "shading": classification == "peaks"}}
                data, stats, _ = render(scene, tmp, f"s{i}{classification}")
                c = contrast(data)
                print(f"first picture {name} {classification}: contrast {c:.3f}, tf_source {stats['tf_source']}")
                assert stats["tf_source"] == "auto" and stats["warnings"] == [], stats
                assert c >= MIN_CONTRAST, (name, classification, c)


def test_the_bound_rejects_a_picture_with_little_to_see():
    """A faint haze (the same volume with a hundredth of a sensible opacity) falls below the bound,
    so the bound can fail. The grey ramp seen straight along an axis, what a scene without a TF
    or camera used to give, is measured and printed for comparison."""
    with Server() as s:
        faint = {"volume": "heptane_151", "image": {"width": 256, "height": 256},
                 "tf": {"points": [[0, 0, 0, 0, 0], [60, 0.2, 0.3, 0.8, 0.0002], [255, 1, 1, 1, 0.0005]]}}
        _, data = post(s, "", faint)
        c = contrast(data)
        print(f"faint haze: contrast {c:.3f}")
        assert c < MIN_CONTRAST, c
        status, _, body = http(s, "/api/volumes/heptane_151")
        info = json.loads(body)
        lo, hi = info["range"]
        box = [(n - 1) * sp for n, sp in zip(info["dims"], info["spacing"])]
        center = [o + b / 2 for o, b in zip(info["origin"], box)]
        radius = sum(b * b for b in box) ** 0.5 / 2
        eye = [center[0], center[1], center[2] + radius / 0.25881904510252074]  # sin(15 degrees)
        old = {"volume": "heptane_151", "image": {"width": 256, "height": 256},
               "camera": {"eye": eye, "center": center, "up": [0, 1, 0], "fov_y": 30},
               "tf": {"points": [[lo, 0, 0, 0, 0], [hi, 1, 1, 1, 1]]}}
        _, data = post(s, "", old)
        print(f"grey ramp along z (the old default): contrast {contrast(data):.3f}")


def test_peaks_without_a_peak_warn():
    ramp = {"points": [[0, 0, 0, 0, 0], [255, 1, 1, 1, 0.5]]}
    body = {"volume": "heptane_151", "image": {"width": 64, "height": 64}, "tf": ramp,
            "render": {"classification": "peaks"}}
    with Server() as s:
        headers, data = post(s, "", body)
        assert "no opacity peak" in headers.get("X-Warning", ""), headers
    with tempfile.TemporaryDirectory() as tmp:
        _, stats, err = render(dict(body, volume=str(DATA / "heptane_151.nrrd")), tmp, "ramp")
        assert any("no opacity peak" in w for w in stats["warnings"]), stats
        assert "warning: classification peaks" in err, err


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    import script_tests

    script_tests.run(globals())
