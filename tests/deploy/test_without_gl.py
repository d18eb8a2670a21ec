#!/usr/bin/env python3
"""PEAKCAST_WITH_GL=OFF builds a server without any GL library that renders on the CPU backend:
`render` and `serve` (a REST still) work, `--backend gl` is refused by name. The build lives
beside the main one (PEAKCAST_NOGL_BUILD, same depth, so ccache reuses the main build's objects)
and is incremental across runs."""
import json, os, pathlib, re, shutil, signal, subprocess, sys, tempfile, time, urllib.request

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("PEAKCAST_NOGL_BUILD", ROOT / "build-nogl"))
DATA = ROOT / "tests/data"
SCENE = {"volume": str(DATA / "heptane_151.nrrd"), "image": {"width": 96, "height": 96},
         "render": {"classification": "peaks", "shading": True}}


def peakcast():
    return BUILD / "server/peakcast"


def build():
    if not (BUILD / "CMakeCache.txt").exists():
        args = ["cmake", "-S", str(ROOT), "-B", str(BUILD), "-DCMAKE_BUILD_TYPE=Release", "-DPEAKCAST_WITH_GL=OFF",
                "-DPEAKCAST_BUILD_TESTS=OFF", "-DPEAKCAST_WITH_MPI=OFF"]
        if shutil.which("ccache"):
            args += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache", "-DCMAKE_C_COMPILER_LAUNCHER=ccache"]
        subprocess.run(args, check=True, stdout=subprocess.DEVNULL)
    t0 = time.time()
    subprocess.run(["cmake", "--build", str(BUILD), "--target", "peakcast", f"-j{os.cpu_count() or 2}"], check=True,
                   stdout=subprocess.DEVNULL)
    print(f"build without GL: {time.time() - t0:.0f} s", flush=True)


def test_no_gl_library_is_linked():
    """peakcast's own dependencies (a library may bring GL on its own: OpenImageIO's OpenCV does)."""
    dynamic = subprocess.run(["readelf", "-d", str(peakcast())], capture_output=True, text=True, check=True).stdout
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic)
    assert any(n.startswith("libturbojpeg") for n in needed), needed  # the list was read
    for gl in ("libEGL", "libepoxy", "libGL", "libOpenGL"):
        assert not any(n.startswith(gl) for n in needed), f"{gl} linked: {needed}"


def test_render_draws_on_the_cpu_backend():
    with tempfile.TemporaryDirectory() as tmp:
        scene, out, stats = (pathlib.Path(tmp) / n for n in ("s.json", "s.png", "st.json"))
        scene.write_text(json.dumps(SCENE))
        subprocess.run([peakcast(), "render", scene, "-o", out, "--stats", stats], check=True, capture_output=True,
                       timeout=120)
        st = json.loads(stats.read_text())
        assert st["backend"] == "cpu" and st["variant"].startswith("cpu"), st
        assert out.stat().st_size > 1000
        # gl asked for by name: refused, saying why.
        r = subprocess.run([peakcast(), "render", scene, "-o", out, "--backend", "gl"], capture_output=True, text=True,
                           timeout=60)
        assert r.returncode != 0 and "built without GL" in r.stderr, (r.returncode, r.stderr)


def test_serve_answers_a_rest_still():
    p = subprocess.Popen([peakcast(), "serve", "--port", "0", "--data", str(DATA), "--volume",
                          str(DATA / "heptane_151.nrrd")], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True)
    try:
        port = None
        for _ in range(200):
            line = p.stdout.readline()
            m = re.search(r"serving on http://[\d.]+:(\d+)", line)
            if m:
                port = int(m.group(1))
                break
        assert port, "the server did not start"
        health = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/api/health", timeout=30).read())
        assert health["backend"] == "cpu", health
        body = dict(SCENE, volume="heptane_151")
        req = urllib.request.Request(f"http://127.0.0.1:{port}/api/render", data=json.dumps(body).encode(),
                                     headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(req, timeout=120) as r:
            assert r.headers["Content-Type"] == "image/png" and len(r.read()) > 1000
    finally:
        p.send_signal(signal.SIGTERM)
        p.wait(timeout=10)


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    import script_tests

    script_tests.run(globals(), before=build)
