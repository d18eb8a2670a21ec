#!/usr/bin/env python3
"""Video sessions over the wire (docs/streaming.md): the codecs a welcome lists, a codec asked
for by name, key frames where the rules say (first frame, resize, the client's request), the
final frame a still as before, and refusals by name. The pictures themselves are checked in
Chromium's decoder (tests/browser/video.test.mjs) and libavcodec's (net_video_tests)."""
import asyncio, pathlib, sys, time

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from harness import *  # noqa: F401,F403

VIDEO, KEY = 8, 16


async def orbit(c, cam, frames, key_at=(), start=0):
    """Moves the camera `frames` times, each after the last frame came; sends the extra messages
    of `key_at` (frame index -> message) before that move. Returns the interactive frames seen."""
    seen = []
    for i in range(frames):
        if i in key_at:
            await c.send(key_at[i])
        cam = dict(cam, eye=[cam["eye"][0] + 0.3 * (start + i + 1), cam["eye"][1], cam["eye"][2]])
        await c.send({"type": "camera", "camera": cam})
        f = await c.next_frame(final=False)
        seen.append(f)
    return seen, cam


def test_welcome_lists_codecs_and_a_video_session_streams_key_then_delta():
    async def run():
        c = await Client.connect(SERVER)
        w = await c.hello(320, 240)
        codecs = w["capabilities"]["codecs"]
        assert codecs[0] == "jpeg" and "h264" in codecs and "vp9" in codecs, codecs
        assert w["limits"]["max_kbps"] == 3000, w["limits"]
        await c.next_frame(final=True)
        await c.send({"type": "quality", "codec": "h264", "kbps": 2000})
        seen, cam = await orbit(c, w["state"]["camera"], 6)
        flags = [f["flags"] for f in seen]
        assert all(f & VIDEO for f in flags), flags
        assert flags[0] & KEY, "the stream starts with a key frame"
        assert not any(f & KEY for f in flags[1:]), f"only the first is a key frame: {flags}"
        # The coded size is the view at interactive_scale (0.5), even: 160 x 120.
        assert {(f["width"], f["height"]) for f in seen} == {(160, 120)}
        assert seen[0]["image"][:4] == b"\x00\x00\x00\x01", "H.264 in Annex B, parameter sets in-band"
        stats = [t for t in c.texts if t["type"] == "stats" and not t["final"]]
        assert stats[-1]["codec"] == "h264" and stats[-1]["kbps"] > 0, stats[-1]
        # At rest: the final frame is a still as before, not video.
        final = await c.next_frame(final=True)
        assert not final["flags"] & VIDEO and final["image"][:2] == b"\xff\xd8", final["flags"]
        # The next motion goes on with the same stream (the still is outside it): no key frame.
        more, cam = await orbit(c, cam, 2, start=6)
        assert all(f["flags"] & VIDEO and not f["flags"] & KEY for f in more), [f["flags"] for f in more]
        await c.close()
    asyncio.run(run())


def test_key_frames_on_resize_on_request_and_on_a_new_connection():
    async def run():
        c = await Client.connect(SERVER)
        w = await c.hello(320, 240)
        await c.next_frame(final=True)
        await c.send({"type": "quality", "codec": "vp9"})
        seen, cam = await orbit(c, w["state"]["camera"], 9, key_at={
            3: {"type": "keyframe"},
            6: {"type": "viewport", "width": 400, "height": 300}})
        keys = [i for i, f in enumerate(seen) if f["flags"] & KEY]
        assert keys == [0, 3, 6], f"key frames at {keys}, flags {[f['flags'] for f in seen]}"
        assert (seen[6]["width"], seen[6]["height"]) == (200, 150)
        stats = [t for t in c.texts if t["type"] == "stats" and not t["final"]]
        assert stats[-1]["codec"] == "vp9", stats[-1]
        await c.close()
        # Reconnecting is a new session: its stream starts with a key frame again.
        c = await Client.connect(SERVER)
        w = await c.hello(320, 240)
        await c.next_frame(final=True)
        await c.send({"type": "quality", "codec": "vp9"})
        seen, _ = await orbit(c, w["state"]["camera"], 2)
        assert seen[0]["flags"] & KEY and not seen[1]["flags"] & KEY, [f["flags"] for f in seen]
        await c.close()
    asyncio.run(run())


def test_a_client_that_lags_loses_no_video_frame():
    """Newest-wins before encoding, never after: a video frame the next one refers to is never
    replaced in the send queue, so every frame id the client receives follows the one before
    among the video frames (no gap the decoder would stumble over)."""
    async def run():
        c = await Client.connect(SERVER)
        w = await c.hello(320, 240)
        await c.next_frame(final=True)
        await c.send({"type": "quality", "codec": "h264"})
        cam = w["state"]["camera"]
        for i in range(40):  # much faster than frames come: the server renders what it can
            cam = dict(cam, eye=[cam["eye"][0] + 0.2, cam["eye"][1], cam["eye"][2]])
            await c.send({"type": "camera", "camera": cam})
            await asyncio.sleep(0.005)
        t0 = time.time()
        while time.time() - t0 < 3:
            try:
                await c.recv(0.5)
            except asyncio.TimeoutError:
                break
        video = [f for f in c.frames if f["flags"] & VIDEO]
        assert len(video) >= 2, len(video)
        assert video[0]["flags"] & KEY
        # Frame ids count every frame the session rendered: a frame replaced in the queue would
        # leave a gap. From the first video frame on, none.
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
