#!/usr/bin/env python3
"""The image is really built and run. docker/build-image.sh builds it (buildah, vfs, chroot,
on a debootstrap base when no registry answers); the server runs inside on the host's loopback; its
health answers, a REST render equals the host's `peakcast render`, it runs as a non-root user, and
it exits within 5 s of SIGTERM. Prints the image size and the build time."""
import json, os, pathlib, re, signal, socket, subprocess, sys, tempfile, time, urllib.request

sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "net"))
from harness import decode_image, psnr, http  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
PEAKCAST = os.environ["PEAKCAST_BIN"]
IMAGE = os.environ.get("PEAKCAST_TEST_IMAGE", "localhost/peakcast:ctest")
BUILDAH = ["buildah", "--storage-driver", "vfs"]
SCENE = {"image": {"width": 160, "height": 128},
         "camera": {"eye": [75, -160, 230], "center": [75, 75, 75], "up": [0, 0, 1], "fov_y": 30},
         "tf": {"points": [[0, 0, 0, 0, 0], [90, 0.2, 0.5, 1.0, 0.04], [140, 0.2, 0.5, 1, 0], [199, 1, 0.1, 0, 0],
                           [200, 1, 0.1, 0, 0.9], [201, 1, 0.1, 0, 0], [255, 1, 1, 1, 0]]},
         "render": {"classification": "peaks", "shading": True, "filter": "tricubic"}}


class Base:  # what harness.http needs
    def __init__(self, port):
        self.base = f"http://127.0.0.1:{port}"


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw).stdout


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def server_pids():
    """peakcast serve processes inside a chroot (the container's), by /proc."""
    pids = []
    for p in pathlib.Path("/proc").iterdir():
        if not p.name.isdigit():
            continue
        try:
            cmd = (p / "cmdline").read_bytes().split(b"\0")
            if len(cmd) > 1 and cmd[0].endswith(b"peakcast") and cmd[1] == b"serve" and os.readlink(p / "root") != "/":
                pids.append(int(p.name))
        except OSError:
            pass
    return pids


def uid_of(pid):
    status = pathlib.Path(f"/proc/{pid}/status").read_text()
    return int(re.search(r"^Uid:\s+(\d+)", status, re.M).group(1))


def main():
    failures = []

    def check(cond, what):
        print(("ok   " if cond else "FAIL ") + what, flush=True)
        if not cond:
            failures.append(what)

    start = time.time()
    build = subprocess.run(["bash", str(ROOT / "docker/build-image.sh")], env=dict(os.environ, PEAKCAST_IMAGE=IMAGE),
                           capture_output=True, text=True)
    built = [l for l in build.stdout.splitlines() if l.startswith("build-image:")]
    print("\n".join(built))
    if build.returncode != 0:
        print(build.stdout[-4000:], build.stderr[-4000:])
        check(False, "docker/build-image.sh builds the image")
        return failures
    print(f"image build: {time.time() - start:.0f} s wall")

    config = json.loads(run(BUILDAH + ["inspect", "--type", "image", IMAGE]))["Docker"]["config"]
    check(config.get("User", "").split(":")[0] not in ("", "root", "0"), f"non-root USER ({config.get('User')})")
    check("8080/tcp" in (config.get("ExposedPorts") or {}), "EXPOSE 8080")
    check("/data" in (config.get("Volumes") or {}), "VOLUME /data")
    health = (config.get("Healthcheck") or {}).get("Test") or []
    check(health[:1] in (["CMD"], ["CMD-SHELL"]), f"HEALTHCHECK ({health})")
    check(config.get("Entrypoint") == ["peakcast", "serve"], f"ENTRYPOINT peakcast serve ({config.get('Entrypoint')})")

    ctr = run(BUILDAH + ["from", "--name", f"peakcast-ctest-{os.getpid()}", IMAGE]).strip()
    data = tempfile.mkdtemp()
    proc = None
    try:
        inside = lambda *cmd: subprocess.run(BUILDAH + ["run", "--isolation", "chroot", ctr, "--", *cmd],
                                             capture_output=True, text=True, timeout=60)
        check(inside("sh", "-c", "command -v peakcast").stdout.strip() == "/usr/local/bin/peakcast", "peakcast on PATH")
        ldd = inside("ldd", "/usr/local/bin/peakcast").stdout
        check("not found" not in ldd and "libOpenImageIO" in ldd, "every library of the binary is in the image")
        version = inside("peakcast", "--version").stdout.strip()
        check(version.startswith("peakcast "), f"peakcast --version runs inside: {version}")

        # A volume in the data volume, mounted read-only from the host. `buildah run` mounts an
        # anonymous volume over the image's VOLUME /data (`docker run -v` would replace it), so the
        # host folder goes beneath it: still inside the image's configured data directory.
        pathlib.Path(data, "heptane.nrrd").write_bytes((ROOT / "tests/data/heptane_151.nrrd").read_bytes())
        os.chmod(data, 0o755)
        port = free_port()
        server = Base(port)
        # The image's own entrypoint and environment; only the port and a token come from here.
        cmd = BUILDAH + ["run", "--isolation", "chroot", "-e", f"PEAKCAST_PORT={port}", "-e", "PEAKCAST_TOKEN=ctest",
                         "-v", f"{data}:/data/host:ro", ctr, "--", *config["Entrypoint"]]
        t0 = time.time()
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = proc.stdout.readline()
        check("serving on" in line, f"the server starts inside ({time.time() - t0:.1f} s): {line.strip()}")
        if "serving on" not in line:
            proc.wait(timeout=30)
            print(proc.stderr.read()[-3000:])
            return failures
        status, _, body = http(server, "/api/health")
        check(status == 200 and json.loads(body)["status"] == "ok", "GET /api/health from the host: 200 ok")
        hc = subprocess.run(BUILDAH + ["run", "--isolation", "chroot", "-e", f"PEAKCAST_PORT={port}", ctr, "--",
                                       *health[1:]], capture_output=True, timeout=30)
        check(hc.returncode == 0, "the image's HEALTHCHECK command passes")
        check(http(server, "/api/volumes")[0] == 401, "the token from the environment is required")
        status, _, body = http(server, "/docs/scenes.md")
        check(status == 200 and b"## Clipping" in body, "the docs the client links to are served (/docs/scenes.md)")

        scene = dict(SCENE, volume="/data/host/heptane.nrrd")
        status, headers, png = http(server, "/api/render", "POST", json.dumps(scene).encode(),
                                    {"Authorization": "Bearer ctest"})
        check(status == 200, f"REST render inside the container ({status})")
        with tempfile.TemporaryDirectory() as tmp:
            pathlib.Path(tmp, "s.json").write_text(json.dumps(dict(SCENE, volume=f"{data}/heptane.nrrd")))
            run([PEAKCAST, "render", f"{tmp}/s.json", "-o", f"{tmp}/host.png"])
            if status == 200:
                value = psnr(decode_image(png), decode_image(pathlib.Path(tmp, "host.png").read_bytes()))
                check(value >= 48.0, f"REST render in the container equals the host's peakcast render "
                                     f"(PSNR {value:.1f} dB; 200 = identical)")

        pids = server_pids()
        check(len(pids) == 1, f"one server process in the container ({pids})")
        if pids:
            uid = uid_of(pids[0])
            check(uid != 0, f"the server runs as uid {uid}, not root")
            t0 = time.time()
            os.kill(pids[0], signal.SIGTERM)
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                pass
            took = time.time() - t0
            check(proc.returncode is not None and took <= 5.0,
                  f"exits within 5 s of SIGTERM ({took:.2f} s, exit {proc.returncode})")
            check(proc.returncode == 0, "exit status 0 after SIGTERM")
    finally:
        if proc and proc.poll() is None:
            for pid in server_pids():
                os.kill(pid, signal.SIGKILL)
            proc.kill()
        if proc:
            err = proc.stderr.read()
            logs = [l for l in err.splitlines() if l.startswith("{")]
            check(bool(logs) and all("level" in json.loads(l) for l in logs), f"JSON logs ({len(logs)} lines)")
        subprocess.run(BUILDAH + ["rm", ctr], capture_output=True)
        subprocess.run(["rm", "-rf", data])
    return failures


if __name__ == "__main__":
    failures = main()
    print(f"{'FAILED: ' + '; '.join(failures) if failures else 'all container checks passed'}")
    sys.exit(1 if failures else 0)
