#!/usr/bin/env python3
"""Independent check of the scene conventions (docs/scenes.md): the same scenes rendered by VTK's
vtkFixedPointVolumeRayCastMapper (Debian's python3-vtk9, offscreen under xvfb-run) and by
`peakcast render`. Measured on llvmpipe: 41.0-42.2 dB; the bound 38 dB. A mirrored image (a
broken row order or camera handedness) scores under 25 dB, checked too, so the test can fail."""
import json, math, pathlib, subprocess, sys, tempfile

from PIL import Image, ImageOps

ROOT = pathlib.Path(__file__).resolve().parents[2]
PEAKCAST = sys.argv[1]
HERE = pathlib.Path(__file__).parent


def psnr(a, b):
    pa, pb = a.convert("RGB").tobytes(), b.convert("RGB").tobytes()
    se = sum((x - y) ** 2 for x, y in zip(pa, pb))
    return 200.0 if se == 0 else 20 * math.log10(255.0 / math.sqrt(se / len(pa)))


failures = 0
scenes = sorted((HERE / "vtk_scenes").glob("*.json"))
with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)
    for path in scenes:
        scene = json.loads(path.read_text())
        volume = ROOT / "tests/data" / scene["volume"]
        mha = tmp / (path.stem + ".mha")  # VTK reads MetaImage reliably (not headsq's multi-file NRRD)
        subprocess.run([PEAKCAST, "convert", str(volume), str(mha)], check=True, capture_output=True)
        (tmp / "vtk.json").write_text(json.dumps(dict(scene, volume=str(mha))))
        (tmp / "pc.json").write_text(json.dumps(dict(scene, volume=str(volume))))
        subprocess.run(["xvfb-run", "-a", "/usr/bin/python3", str(HERE / "vtk_render.py"), str(tmp / "vtk.json"),
                        str(tmp / "vtk.png")], check=True, capture_output=True)
        subprocess.run([PEAKCAST, "render", str(tmp / "pc.json"), "-o", str(tmp / "pc.png")], check=True,
                       capture_output=True)
        vtk_img, pc_img = Image.open(tmp / "vtk.png"), Image.open(tmp / "pc.png")
        value, flipped = psnr(pc_img, vtk_img), psnr(ImageOps.flip(pc_img), vtk_img)
        mirrored = psnr(ImageOps.mirror(pc_img), vtk_img)
        ok = value >= 38.0 and flipped < 25.0 and mirrored < 25.0
        failures += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {path.stem}: peakcast vs VTK {value:.1f} dB "
              f"(upside down {flipped:.1f}, mirrored {mirrored:.1f})")
print(f"{len(scenes) - failures} passed, {failures} failed")
sys.exit(1 if failures else 0)
