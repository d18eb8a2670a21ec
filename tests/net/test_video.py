#!/usr/bin/env python3
"""Video sessions over the wire (docs/streaming.md): the codecs a welcome lists, a codec asked
for by name, key frames where the rules say (first frame, resize, the client's request), the
final frame a still as before, and refusals by name. The pictures themselves are checked in
Chromium's decoder (tests/browser/video.test.mjs) and libavcodec's (net_video_tests)."""
import asyncio, pathlib, sys, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

VIDEO, KEY = 8, 16


async def drag(c, cam, seconds, every=0.04):
    """Moves the camera every `every` seconds for `seconds`, as a mouse drag does (the input is
    never quiet for the still delay, so frames are interactive however slow the build), receiving
    meanwhile. Returns the interactive frames received and the camera at the end."""
    n0 = len(c.frames)
    t0 = time.time()
    while time.time() - t0 < seconds:
        cam = dict(cam, eye=[cam["eye"][0] + 0.05, cam["eye"][1], cam["eye"][2]])
        await c.send({"type": "camera", "camera": cam})
        try:
            while True:
                await c.recv(every)
        except asyncio.TimeoutError:
            pass
    return [f for f in c.frames[n0:] if not f["final"]], cam


async def video_session(codec, width=320, height=240, **quality):
    """A session at rest that streams `codec`: the final frame after the switch has come."""
    c = await Client.connect(SERVER)
    w = await c.hello(width, height)
    await c.next_frame(final=True)
    await c.send({"type": "quality", "codec": codec, **quality})
    await c.next_frame(final=True)  # the still the quality change re-sends
    return c, w


def keys(frames):
    return [i for i, f in enumerate(frames) if f["flags"] & KEY]


def test_welcome_lists_codecs_and_a_video_session_streams_key_then_delta():
    async def run():
        c = await Client.connect(SERVER)
        w = await c.hello(320, 240)
        codecs = w["capabilities"]["codecs"]
        assert codecs[0] == "jpeg" and "h264" in codecs and "vp9" in codecs, codecs
        assert w["limits"]["max_kbps"] == 3000, w["limits"]
        await c.close()
        c, w = await video_session("h264", kbps=2000)
        seen, cam = await drag(c, w["state"]["camera"], 1.5)
        assert len(seen) >= 2, len(seen)
        flags = [f["flags"] for f in seen]
        assert all(f & VIDEO for f in flags), flags
        assert keys(seen) == [0], f"the stream starts with a key frame, and only that: {flags}"
        # The coded size is the view at interactive_scale (0.5), even: 160 x 120, whatever size the
        # frame budget rendered at.
        assert {(f["width"], f["height"]) for f in seen} == {(160, 120)}
        assert seen[0]["image"][:4] == b"\x00\x00\x00\x01", "H.264 in Annex B, parameter sets in-band"
        stats = [t for t in c.texts if t["type"] == "stats" and not t["final"]]
        assert stats[-1]["codec"] == "h264" and stats[-1]["kbps"] > 0, stats[-1]
        # At rest: the final frame is a still as before, not video.
        final = await c.next_frame(final=True)
        assert not final["flags"] & VIDEO and final["image"][:2] == b"\xff\xd8", final["flags"]
        # The next motion goes on with the same stream (the still is outside it): no key frame.
        more, cam = await drag(c, cam, 1.0)
        assert more and all(f["flags"] & VIDEO for f in more) and not keys(more), [f["flags"] for f in more]
        await c.close()
    asyncio.run(run())


def test_key_frames_on_resize_on_request_and_on_a_new_connection():
    async def run():
        c, w = await video_session("vp9")
        a, cam = await drag(c, w["state"]["camera"], 1.0)
        assert a and keys(a) == [0], [f["flags"] for f in a]
        # Asked for: the next frame encoded is a key frame (up to 2 frames were in flight already).
        await c.send({"type": "keyframe"})
        b, cam = await drag(c, cam, 1.0)
        assert len(keys(b)) == 1 and keys(b)[0] <= 2, [f["flags"] for f in b]
        # A resize: a new coded size, whose first frame is a key frame, and only that one.
        await c.send({"type": "viewport", "width": 400, "height": 300})
        r, cam = await drag(c, cam, 1.5)
        new = [f for f in r if (f["width"], f["height"]) == (200, 150)]
        assert new and keys(new) == [0], [(f["width"], f["flags"]) for f in r]
        stats = [t for t in c.texts if t["type"] == "stats" and not t["final"]]
        assert stats[-1]["codec"] == "vp9", stats[-1]
        await c.close()
        # Reconnecting is a new session: its stream starts with a key frame again.
        c, w = await video_session("vp9")
        seen, _ = await drag(c, w["state"]["camera"], 1.0)
        assert seen and keys(seen) == [0], [f["flags"] for f in seen]
        await c.close()
    asyncio.run(run())


def test_a_client_that_lags_loses_no_video_frame():
    """Newest-wins before encoding, never after: a video frame the next one refers to is never
    replaced in the send queue. Frame ids count every frame the session rendered, so a frame
    replaced in the queue would leave a gap among the ids received."""
    async def run():
        c, w = await video_session("h264")
        seen, _ = await drag(c, w["state"]["camera"], 2.0, every=0.005)  # far faster than frames come
        video = [f for f in seen if f["flags"] & VIDEO]
        assert len(video) >= 2 and video[0]["flags"] & KEY, [f["flags"] for f in seen]
        ids = [f["id"] for f in c.frames if f["id"] >= video[0]["id"]]
        assert ids == list(range(ids[0], ids[0] + len(ids))), ids
        await c.close()
    asyncio.run(run())


def test_unknown_codec_and_bad_rates_are_refused_by_name():
    async def run():
        c = await Client.connect(SERVER)
        await c.hello(160, 120)
        for bad, needle in [({"codec": "mpeg2"}, "'mpeg2' is not a codec this server encodes (jpeg, h264, vp9"),
                            ({"codec": 7}, "quality.codec"),
                            ({"kbps": 10}, "quality.kbps"),
                            ({"kbps": 1e9}, "quality.kbps")]:
            await c.send({"type": "quality", **bad})
            e = await c.next_text("error")
            assert e["code"] == "bad_message" and needle in e["message"], (bad, e)
        await c.send({"type": "keyframe", "now": True})
        e = await c.next_text("error")
        assert e["code"] == "bad_message" and "now" in e["message"], e
        # A JPEG session that asks for a key frame: nothing to do, nothing refused.
        before = len(c.texts)
        await c.send({"type": "keyframe"})
        await c.send({"type": "ping", "id": "after"})
        assert (await c.next_text("pong"))["id"] == "after"
        assert not [t for t in c.texts[before:] if t["type"] == "error"], c.texts[before:]
        await c.close()
    asyncio.run(run())


if __name__ == "__main__":
    with Server("--max-kbps", "3000") as SERVER:
        run_tests([test_welcome_lists_codecs_and_a_video_session_streams_key_then_delta,
                   test_key_frames_on_resize_on_request_and_on_a_new_connection,
                   test_a_client_that_lags_loses_no_video_frame,
                   test_unknown_codec_and_bad_rates_are_refused_by_name])
