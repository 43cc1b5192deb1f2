"""The live server over loopback: an in-process uvicorn on a free port, clients from ``websockets``.

Speech is real (espeak-ng); the head is the generic one when built, else the procedural head (the
face goes out as the FBA bitstream either way, so nothing differs). The long test plays
60 s of speech at real time, so it takes about a minute (mostly waiting on the client's clock).
"""
from __future__ import annotations

import json
import time

import numpy as np
import pytest
from websockets.sync.client import connect

from mpeg4fa.decoded import resolve
from mpeg4fa.fba import decode
from mpeg4fa.serve.app import create_app
from mpeg4fa.serve.client import audio_samples, play
from serve.live_server import face_for_tests, running

WINDOW, CHUNK, STALL = 2.0, 0.2, 2.0
SHORT = "(joy, 40, 0.5) Hello there. How are you today? I am fine, thank you."
SENTENCES = ["The quick brown fox jumps over the lazy dog near the bank of the river.",
             "(surprise, 30, 0.4) Nobody expected the weather to turn so quickly this afternoon.",
             "We walked along the old road, talking about music, books and the places we had seen.",
             "(joy, 45, 0.6) Then the sun came out again, and everything looked bright and new."]


@pytest.fixture(scope="module")
def app():
    return create_app(face_for_tests(), window=WINDOW, chunk=CHUNK, stall_timeout=STALL, warm=True)


@pytest.fixture(scope="module")
def base(app):
    with running(app) as url:
        yield url


def ws_url(base: str) -> str:
    return base.replace("http://", "ws://") + "/ws"


def wait_until(check, seconds: float = 15.0) -> None:
    deadline = time.monotonic() + seconds
    while not check():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.02)


def test_text_to_frames_latency_and_what_the_frames_are(app, base):
    played = play(ws_url(base), SHORT, speed=4.0)
    print(f"\nfirst frame {played.first_frame_after * 1e3:.0f} ms after say (client), "
          f"{played.done['first_frame_after'] * 1e3:.0f} ms (server); {played.frames} frames, "
          f"{len(played.segments)} segments, {played.audio_seconds:.2f} s audio")
    assert not played.errors and played.done and not played.done["stopped"]
    assert len(played.segments) == 3 and played.underruns == 0
    assert played.first_frame_after is not None and played.done["first_frame_after"] is not None
    times = []
    for seg in played.segments:  # every segment is a complete stream: what the client decoded is its frames
        stream = decode(seg["fba"])
        assert len(stream) == seg["frames"] and len(seg["fba"]) == seg["bytes"]
        times += (seg["start"] + stream.timestamps).tolist()
    assert played.times == pytest.approx(times, abs=1e-9) and played.frames == played.done["frames"]
    opened = max(int(resolve(decode(seg["fba"]))[:, 2].max()) for seg in played.segments)
    assert opened > 100  # the jaw opens (FAP 3, in MNS units)
    # the face as the bitstream itself: at most 2 kbit/s of speech (issue 31), message heads included
    face_kbps = played.face_bytes * 8 / played.done["duration"] / 1000
    assert face_kbps <= 2.0, f"{face_kbps:.2f} kbit/s of face data"
    segs = played.segments
    assert [s["start"] for s in segs[1:]] == pytest.approx([s["start"] + s["duration"] for s in segs[:-1]])
    assert played.audio_seconds == pytest.approx(sum(s["duration"] for s in segs), abs=1e-6)
    assert played.done["duration"] == pytest.approx(played.audio_seconds, abs=1e-6)
    assert len(audio_samples(played)) > 0


def test_sixty_seconds_of_speech_delivered_in_real_time(app, base):
    text = " ".join(SENTENCES * 4)  # about 60 s at espeak's default rate
    # at real time (1x): a faster client clock made the test a throughput race on a loaded 2-core machine
    # (CI saw 4 items up to 0.34 s late at 3x); at 1x the producer has ~50x headroom
    played = play(ws_url(base), text, speed=1.0, prebuffer=0.5, timeout=180)
    media = played.done["duration"]
    print(f"\n{media:.1f} s of speech in {played.wall:.1f} s at 1x: {played.frames} frames, "
          f"{played.underruns} underruns (max {played.max_lateness * 1e3:.0f} ms late), "
          f"at most {played.max_ahead:.2f} s of audio ({played.max_face_ahead:.2f} s of face) held ahead, "
          f"{played.reports} reports, {played.face_bytes * 8 / media:.0f} bit/s of face data")
    assert not played.errors and not played.done["stopped"] and media > 50
    assert played.underruns == 0, f"{played.underruns} items came after their time (worst {played.max_lateness:.3f} s)"
    assert played.max_ahead <= WINDOW + CHUNK + 1e-6  # flow control: never more than the window ahead
    assert played.wall >= media - WINDOW - CHUNK  # paced by the client, not sent at once
    record = app.state.live.utterances[-1]
    assert record["sentences"] == 16 and record["waits"] > 0


def test_a_client_that_disconnects_mid_speech(app, base):
    before = len(app.state.live.utterances)
    with connect(ws_url(base), origin=base) as ws:
        json.loads(ws.recv(timeout=10))
        ws.send(json.dumps({"type": "say", "text": " ".join(SENTENCES)}))
        while True:
            message = ws.recv(timeout=10)
            if isinstance(message, bytes) and message[:4] == b"FBA1":
                break
    wait_until(lambda: len(app.state.live.utterances) > before and app.state.live.connections == 0)
    record = app.state.live.utterances[-1]
    assert record["stopped"] and not record["stalled"] and record["error"] is None
    assert record["duration"] < 10.0  # it stopped early: the four sentences are about 16 s
    played = play(ws_url(base), "Still here.", speed=4.0)  # the server goes on serving
    assert played.done and not played.errors


def test_a_client_that_stalls_is_closed_after_the_window(app, base):
    before = len(app.state.live.utterances)
    received = 0.0
    with connect(ws_url(base), origin=base) as ws:
        json.loads(ws.recv(timeout=10))
        ws.send(json.dumps({"type": "say", "text": " ".join(SENTENCES)}))
        started = time.monotonic()
        error, rate, face_starts = None, None, []
        try:
            while error is None:  # reads what comes, never reports its buffer
                message = ws.recv(timeout=STALL + 10)
                if isinstance(message, bytes):
                    if message[:4] == b"FBA1":  # a sentence's face goes out whole, once its start is in the window
                        face_starts.append(np.frombuffer(message[4:12], "<f8")[0])
                    if message[:4] == b"AUD1":
                        t = np.frombuffer(message[4:12], "<f8")[0]
                        received = max(received, t + (len(message) - 12) / 2 / rate)
                    continue
                data = json.loads(message)
                if data["type"] == "segment":
                    rate = data["rate"]
                elif data["type"] == "error":
                    error = data
            with pytest.raises(Exception):  # then the server closes the connection
                ws.recv(timeout=10)
        finally:
            waited = time.monotonic() - started
    assert error["where"] == "flow" and "stalled" in error["error"]
    assert ws.close_code == 1008
    assert received <= WINDOW + CHUNK + 1e-6  # one window of audio went out, nothing beyond it
    assert face_starts and max(face_starts) < WINDOW  # and the sentences that start in it
    assert waited >= STALL
    wait_until(lambda: len(app.state.live.utterances) > before and app.state.live.connections == 0)
    assert app.state.live.utterances[-1]["stalled"]


BAD = [
    ("not json", "message", "not JSON"),
    ("[1, 2]", "message", "JSON object"),
    ('{"text": "hi"}', "type", "no \"type\""),
    ('{"type": "shout", "text": "hi"}', "type", "unknown type"),
    ('{"type": "say"}', "text", "Field required"),
    ('{"type": "say", "text": ""}', "text", "at least 1 character"),
    ('{"type": "say", "text": "hi", "volume": 3}', "volume", "Extra inputs"),
    ('{"type": "say", "text": "hi", "lang": "fr"}', "lang", "'auto', 'en' or 'zh'"),
    ('{"type": "say", "text": "' + "a" * 20_001 + '"}', "text", "at most 20000"),
    ('{"type": "buffer", "received": -1, "buffered": 0}', "received", "greater than or equal to 0"),
    ('{"type": "buffer", "received": 1}', "buffered", "Field required"),
    ('{"type": "say", "text": "Hello (joy, 99, 1) there"}', "text:1:13", "intensity"),
    ('{"type": "say", "text": "(joy, 20, 1)"}', "text", "nothing to speak"),
    ("[" * 100_000, "message", "nested more than 64 levels"),  # issue 26: this closed the socket (1006)
]


def test_malformed_messages_get_one_clear_error_and_the_connection_goes_on(base):
    with connect(ws_url(base), origin=base) as ws:
        json.loads(ws.recv(timeout=10))
        for raw, where, words in BAD:
            ws.send(raw)
            answer = json.loads(ws.recv(timeout=10))
            assert answer["type"] == "error" and answer["where"] == where, (raw[:60], answer)
            assert words in answer["error"], (raw[:60], answer)
            assert "\n" not in answer["error"]
        ws.send(b"\x00\x01binary")
        answer = json.loads(ws.recv(timeout=10))
        assert answer["where"] == "message" and "binary" in answer["error"]
        # busy, then stop: a done saying it was stopped
        ws.send(json.dumps({"type": "say", "text": " ".join(SENTENCES), "id": "long"}))
        ws.send(json.dumps({"type": "say", "text": "And this?"}))
        kinds = []
        while "busy" not in kinds:
            message = ws.recv(timeout=10)
            if isinstance(message, str):
                data = json.loads(message)
                kinds.append(data.get("where") if data["type"] == "error" else data["type"])
        ws.send(json.dumps({"type": "stop"}))
        while True:
            message = ws.recv(timeout=10)
            if isinstance(message, str) and (data := json.loads(message))["type"] == "done":
                break
        assert data["stopped"] and data["id"] == "long"
    played = play(ws_url(base), "After the errors, a sentence.", speed=4.0)
    assert played.done and not played.errors


def test_http_routes(base):
    import httpx

    with httpx.Client(base_url=base, timeout=60) as http:
        page = http.get("/")
        assert page.status_code == 200 and "/static/js/player.js" in page.text
        assert "./fba/fba.js" in http.get("/static/js/player.js").text  # the page decodes the stream itself
        assert http.get("/vendor/three/three.module.js").status_code == 200
        assert http.get("/vendor/three/addons/loaders/GLTFLoader.js").status_code == 200
        glb = http.get("/static/fap-head.glb")
        assert glb.status_code == 200 and glb.content[:4] == b"glTF"
        assert glb.headers["content-type"] == "model/gltf-binary"
        assert http.get("/head.glb").status_code == 404  # protocol 1's ARKit head: no page uses it
        missing = http.get("/nowhere")
        assert missing.status_code == 404 and missing.json() == {"error": "not found", "where": "/nowhere"}
        info = http.get("/api/info").json()
        assert info["type"] == "hello" and info["window"] == WINDOW
