"""A live `peakcast serve` for the client's tests: started on a free port with an upload folder
of its own and small limits, so every refusal is reached with small arrays."""
import os
import pathlib
import re
import signal
import subprocess
import sys
import threading

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "client-python"))  # importable from the checkout
PEAKCAST = os.environ.get("PEAKCAST_BIN", str(ROOT / "build/server/peakcast"))
DATA = ROOT / "tests/data"

LIMITS = ["--max-upload-mib", "4", "--upload-budget-mib", "10", "--max-uploads", "1", "--upload-timeout", "2",
          "--uploads-per-minute", "60000"]


class Server:
    def __init__(self, tmp, *args):
        self.upload_dir = tmp / "uploads"
        cmd = [PEAKCAST, "serve", "--port", "0", "--data", str(DATA), "--upload-dir", str(self.upload_dir), *args]
        env = {k: v for k, v in os.environ.items() if not k.startswith("PEAKCAST_") or k == "PEAKCAST_BACKEND"}
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
        self.log = []
        for line in self.proc.stdout:
            self.log.append(line)
            m = re.search(r"serving on http://([\d.]+):(\d+)", line)
            if m:
                self.url, self.port = f"http://{m.group(1)}:{m.group(2)}", int(m.group(2))
                break
        else:
            raise RuntimeError("the server did not start:\n" + "".join(self.log))
        threading.Thread(target=lambda: [self.log.append(l) for l in self.proc.stdout], daemon=True).start()

    def files(self):
        """Every file in the upload folder, the incoming area included (names only)."""
        return sorted(str(p.relative_to(self.upload_dir)) for p in self.upload_dir.rglob("*") if p.is_file())

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        self.proc.wait(timeout=10)


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    s = Server(tmp_path_factory.mktemp("server"), *LIMITS)
    yield s
    s.stop()


@pytest.fixture(scope="module")
def guarded(tmp_path_factory):
    """With a token, and the default rate per client (60 a minute, a burst of 10)."""
    s = Server(tmp_path_factory.mktemp("guarded"), "--token", "sesame")
    yield s
    s.stop()


def blobs(shape=(20, 24, 28), dtype=np.uint16, seed=3):
    """A smooth field with structure, indexed [z, y, x]."""
    z, y, x = np.mgrid[0:shape[0], 0:shape[1], 0:shape[2]].astype(np.float64)
    rng = np.random.default_rng(seed)
    f = np.zeros(shape)
    for _ in range(5):
        c = rng.uniform(0, 1, 3) * np.array(shape)
        f += np.exp(-((z - c[0]) ** 2 + (y - c[1]) ** 2 + (x - c[2]) ** 2) / 30.0)
    f /= f.max()
    if np.dtype(dtype).kind == "f":
        return f.astype(dtype)
    info = np.iinfo(dtype)
    return (info.min + f * (info.max - info.min)).astype(dtype)


def no_uploads_left(server, before):
    assert server.files() == before, (before, server.files())
