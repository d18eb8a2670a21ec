#!/usr/bin/python3
"""A time series (an OME-Zarr with a t axis; docs/scenes.md, "Time"): its info says how many time
points, REST renders any of them as the CLI does, a viewer steps through them with camera and TF
kept, the next ones are read ahead so a step to them loads nothing, a share link's time point is
where a viewer starts, and a time point past the last is refused naming `time`."""
import asyncio, json, pathlib, subprocess, sys, tempfile, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
sys.path.insert(0, str(pathlib.Path(__file__).parents[2] / "scripts"))
from harness import *  # noqa: F401,F403
import make_time_series

TMP = tempfile.TemporaryDirectory()
TIMES = 6
make_time_series.write(pathlib.Path(TMP.name, "ball.zarr"), times=TIMES, n=24)
SCENE = {"volume": "ball.zarr", "image": {"width": 64, "height": 48},
         "tf": {"points": [[0, 0, 0, 0, 0], [20000, 0.2, 0.8, 1, 0.05], [60000, 1, 0.8, 0.2, 0.6]]}}


def cli_render(scene, name):
    """`peakcast render` of the scene, the volume given by path: the reference for REST."""
    pathlib.Path(TMP.name, f"{name}.json").write_text(json.dumps(dict(scene, volume="ball.zarr")))
    out = subprocess.run([PEAKCAST, "render", f"{TMP.name}/{name}.json", "-o", f"{TMP.name}/{name}.png"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return Image.open(f"{TMP.name}/{name}.png")


def test_rest_renders_any_time_point_as_the_cli_does():
    with Server("--data", TMP.name, volumes=()) as s:
        pictures = []
        for t in (0, 3, TIMES - 1):
            status, _, png = http(s, "/api/render", "POST", json.dumps(dict(SCENE, time=t)).encode())
            assert status == 200, (t, png[:300])
            pictures.append(decode_image(png))
            assert psnr(pictures[-1], cli_render(dict(SCENE, time=t), f"t{t}")) == 200.0, t
        assert psnr(pictures[0], pictures[1]) < 40 and psnr(pictures[1], pictures[2]) < 40, "the ball moves"
        info = json.loads(http(s, "/api/volumes/ball.zarr")[2])
        assert info["times"] == TIMES and info["time"] == 0 and info["units"] == "µm", info
        listed = [v for v in json.loads(http(s, "/api/volumes")[2])["volumes"] if v["id"] == "ball.zarr"]
        assert len(listed) == 1, "a series is one volume, however many time points are held"
        for bad in (TIMES, 99):
            status, _, body = http(s, "/api/render", "POST", json.dumps(dict(SCENE, time=bad)).encode())
            answer = json.loads(body)
            assert status == 400 and answer["error"] == "bad_scene", (status, answer)
            assert answer["message"].startswith(f"time: time point {bad} is outside the volume's 0..{TIMES - 1}"), answer
        status, _, body = http(s, "/api/render", "POST", json.dumps(dict(SCENE, time=-1)).encode())
        assert status == 400 and "time" in json.loads(body)["message"], body
        status, _, body = http(s, "/api/render", "POST", json.dumps(
            {"volume": "heptane_151.nrrd", "time": 1, "image": {"width": 32, "height": 32}}).encode())
        assert status == 400 and "time: time point 1 is outside the volume's one time point" in json.loads(body)["message"], body
        assert http(s, "/api/health")[0] == 200
    # The CLI refuses a time point past the last by name too.
    pathlib.Path(TMP.name, "bad.json").write_text(json.dumps(dict(SCENE, time=TIMES)))
    out = subprocess.run([PEAKCAST, "render", f"{TMP.name}/bad.json", "-o", f"{TMP.name}/bad.png"],
                         capture_output=True, text=True)
    assert out.returncode != 0 and f"time point {TIMES}" in out.stderr, out.stderr


async def frame_at(c, t, timeout=60):
    """The next final frame whose stats say time point t."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        f = await c.next_frame(final=True, timeout=deadline - time.time())
        st = await c.stats_of(f)
        if st.get("time") == t:
            return f, st
    raise TimeoutError(f"no final frame of time point {t}")


async def test_a_viewer_steps_through_time_with_camera_and_tf_kept():
    with Server("--data", TMP.name, volumes=()) as s:
        c = await Client.connect(s)
        w = await c.hello(96, 72, volume="ball.zarr", state={"tf": SCENE["tf"]})
        assert w["volume"]["times"] == TIMES and "time" not in w["state"], w["state"]
        camera = w["state"]["camera"]
        await frame_at(c, 0)
        await c.send({"type": "time", "time": 2})
        f2, _ = await frame_at(c, 2)
        # The next time points are read ahead: a step to one loads nothing and draws at once.
        await asyncio.sleep(1.0)
        loads = sum(1 for m in c.texts if m.get("type") == "loading")
        await c.send({"type": "time", "time": 3})
        f3, _ = await frame_at(c, 3)
        assert sum(1 for m in c.texts if m.get("type") == "loading") == loads, "time point 3 was held"
        assert f3["camera_version"] == f2["camera_version"] and f3["tf_version"] == f2["tf_version"]
        assert f3["render_version"] > f2["render_version"], "a step is a new picture"
        assert psnr(decode_image(f2["image"]), decode_image(f3["image"])) < 45, "the ball moved"
        # A time point past the last: refused by name, the session goes on at the one it had.
        await c.send({"type": "time", "time": TIMES})
        err = await c.next_text("error")
        assert err["code"] == "bad_message" and err["message"].startswith(f"time: time point {TIMES}"), err
        await c.send({"type": "camera", "camera": camera})
        await frame_at(c, 3)
        for bad in ({"type": "time"}, {"type": "time", "time": -2}, {"type": "time", "time": "3"},
                    {"type": "time", "time": 1, "extra": 1}):
            await c.send(bad)
            assert (await c.next_text("error"))["code"] == "bad_message", bad
        # Many steps at once (a slider dragged): the frames that come are in order, and end at the last.
        before = len(c.texts)
        for t in range(TIMES):
            await c.send({"type": "time", "time": t})
        await frame_at(c, TIMES - 1)
        shown = [m["time"] for m in c.texts[before:] if m.get("type") == "stats"]
        assert shown and shown[-1] == TIMES - 1 and all(a <= b for a, b in zip(shown, shown[1:])), shown
        await c.close()
        # A share link's time point: the viewer starts there.
        d = await Client.connect(s)
        w = await d.hello(96, 72, volume="ball.zarr", state={"time": 4})
        assert w["state"]["time"] == 4 and w["volume"]["time"] == 4, (w["state"].get("time"), w["volume"]["time"])
        await frame_at(d, 4)
        await d.close()
        d = await Client.connect(s)
        await d.send({"type": "hello", "viewport": {"width": 64, "height": 48}, "volume": "ball.zarr",
                      "state": {"time": TIMES}})
        err = await d.next_text("error")
        assert err["code"] == "bad_message" and "time point" in err["message"], err
        await d.close()
        assert s.alive()


if __name__ == "__main__":
    run_tests([test_rest_renders_any_time_point_as_the_cli_does, test_a_viewer_steps_through_time_with_camera_and_tf_kept])
