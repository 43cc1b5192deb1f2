"""The serve microphone over loopback (mpeg4fa/serve/microphone.py): MIC1 audio chunks in, FBA1 faces out on
the same socket, decoded here with the package's decoder; and the guard on the audio messages (size, rate,
order). The audio is espeak-ng speech sent at real time (the server refuses audio faster than that)."""
from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest
from websockets.sync.client import connect

pytest.importorskip("pocketsphinx", reason="the microphone's lip sync needs pocketsphinx (the 'align' extra)")

from mpeg4fa.decoded import resolve  # noqa: E402
from mpeg4fa.fba import decode  # noqa: E402
from mpeg4fa.serve.app import create_app  # noqa: E402
from mpeg4fa.serve.microphone import AHEAD, MAX_CHUNK_BYTES, MIC_KIND  # noqa: E402
from mpeg4fa.serve.protocol import FBA_KIND, pack, unpack  # noqa: E402
from mpeg4fa.spec import FAP_BY_NAME  # noqa: E402
from mpeg4fa.speech.live import LATENCY  # noqa: E402
from mpeg4fa.speech.align.recording import resample  # noqa: E402
from serve.live_server import face_for_tests, running  # noqa: E402

RATE, FPS, CHUNK = 16000, 25.0, 320
JAW = FAP_BY_NAME["open_jaw"].number - 1


@pytest.fixture(scope="module")
def base():
    with running(create_app(face_for_tests(), warm=True)) as url:  # as `serve` starts it
        yield url


def ws_url(base: str) -> str:
    return base.replace("http://", "ws://") + "/ws"


def speech_pcm() -> tuple[np.ndarray, float, float]:
    """0.8 s of silence, 'Open wide and say ah.', 1.2 s of silence (16 kHz int16), and where the speech is."""
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    speech = EspeakEngine().synthesize("Open wide and say ah.")
    x = resample(speech.samples / 32768.0, speech.rate, RATE)
    pcm = np.concatenate([np.zeros(int(0.8 * RATE)), x, np.zeros(int(1.2 * RATE))])
    return np.clip(np.rint(pcm * 32767), -32768, 32767).astype(np.int16), 0.8, 0.8 + len(x) / RATE


def receive_all(ws, until: str, seconds: float = 20.0) -> tuple[list[dict], list[tuple[float, bytes]]]:
    texts, faces = [], []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            message = ws.recv(timeout=max(0.01, deadline - time.monotonic()))
        except TimeoutError:
            break
        if isinstance(message, str):
            texts.append(json.loads(message))
            if until and texts[-1].get("state") == until:
                break
        else:
            kind, t, payload = unpack(message)
            assert kind == FBA_KIND
            faces.append((t, payload))
    return texts, faces


def test_microphone_audio_comes_back_as_a_face_that_speaks(base):
    pcm, start, end = speech_pcm()
    with connect(ws_url(base), origin=base, max_size=None) as ws:
        assert json.loads(ws.recv(timeout=10))["type"] == "hello"
        t0 = time.monotonic()
        for k, i in enumerate(range(0, len(pcm), CHUNK)):
            wait = t0 + k * CHUNK / RATE - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            ws.send(pack(MIC_KIND, i / RATE, pcm[i:i + CHUNK].astype("<i2").tobytes()))
        ws.send(pack(MIC_KIND, len(pcm) / RATE, b""))
        texts, faces = receive_all(ws, until="ended")
    kinds = [m.get("state") or m["type"] for m in texts]
    assert kinds[0] == "started" and kinds[-1] == "ended" and "error" not in kinds, texts
    assert texts[0]["latency"] == pytest.approx(LATENCY) and texts[0]["rate"] == RATE
    times, values = [], []
    for t, payload in faces:  # each message a whole stream of its own, placed at its media time
        stream = decode(payload)
        times += list(t + np.asarray(stream.timestamps))
        values.append(resolve(stream))
    times, values = np.array(times), np.concatenate(values)
    n = math.ceil(len(pcm) / RATE * FPS)
    assert texts[-1]["frames"] == n == len(times) and np.allclose(times, np.arange(n) / FPS, atol=1e-6)
    jaw = values[:, JAW]
    speaking = (times >= start + 0.1) & (times < end - 0.1)
    assert (jaw[speaking] > 0).mean() >= 0.5 and jaw.max() >= 300, jaw[speaking]
    quiet = (times < start - 0.25) | (times > end + 0.3)
    assert quiet.sum() >= 20 and not jaw[quiet].any()


@pytest.mark.parametrize("payload, words", [(b"\x00" * (MAX_CHUNK_BYTES + 2), "at most"), (b"\x00" * 321, "at most")])
def test_an_oversized_or_odd_chunk_is_refused_and_the_connection_goes_on(base, payload, words):
    with connect(ws_url(base), origin=base) as ws:
        json.loads(ws.recv(timeout=10))
        ws.send(pack(MIC_KIND, 0.0, payload))
        answer = json.loads(ws.recv(timeout=10))
        assert answer["type"] == "error" and answer["where"] == "mic" and words in answer["error"]
        ws.send(b"\x00\x01binary")  # not a microphone message: the protocol's own answer
        answer = json.loads(ws.recv(timeout=10))
        assert answer["where"] == "message" and "binary" in answer["error"]
        ws.send(json.dumps({"type": "say", "text": "Hi."}))
        assert json.loads(ws.recv(timeout=20))["type"] == "started"


@pytest.mark.parametrize("t", [1e308, -1e308, 1e300])
def test_a_chunk_time_past_any_clock_is_one_error_and_the_session_goes_on(base, t):
    """Fuzz of 2026-12-07: a chunk at t = 1e308 after one at 0 raised OverflowError (float infinity to integer) in
    the server, whose console showed the traceback while the socket dropped without a word."""
    chunk = np.zeros(1600, np.int16).tobytes()  # 0.1 s
    with connect(ws_url(base), origin=base) as ws:
        json.loads(ws.recv(timeout=10))
        ws.send(pack(MIC_KIND, 0.0, chunk))
        ws.send(pack(MIC_KIND, t, chunk))
        error = None
        while error is None:
            message = ws.recv(timeout=10)
            if isinstance(message, str) and json.loads(message)["type"] == "error":
                error = json.loads(message)
        assert error["where"] == "mic" and "chunks come in order" in error["error"] and len(error["error"]) < 200
        ws.send(pack(MIC_KIND, 0.1, b""))  # the session is still there, and ends
        texts, _ = receive_all(ws, until="ended")
        assert any(m.get("state") == "ended" for m in texts)


def test_audio_faster_than_real_time_and_out_of_order_is_refused(base):
    """The server never listens to more audio than the wall clock since the session's first chunk allows,
    plus AHEAD: a client sending 10 s at once gets errors, and the session holds about what time allowed."""
    chunk = np.zeros(4000, np.int16).tobytes()  # 0.25 s
    with connect(ws_url(base), origin=base, max_size=None) as ws:
        json.loads(ws.recv(timeout=10))
        sent_at = time.monotonic()
        for k in range(40):  # 10 s of audio at once
            ws.send(pack(MIC_KIND, k * 0.25, chunk))
        ws.send(pack(MIC_KIND, 0.0, chunk))  # back to the start
        ws.send(pack(MIC_KIND, 10.0, b""))
        texts, _ = receive_all(ws, until="ended")
        elapsed = time.monotonic() - sent_at
    errors = [m["error"] for m in texts if m["type"] == "error"]
    assert all(m["where"] == "mic" for m in texts if m["type"] == "error")
    assert any("faster than real time" in e for e in errors), errors
    assert any("chunks come in order" in e for e in errors), errors
    ended = [m for m in texts if m.get("state") == "ended"]
    assert ended and ended[0]["seconds"] <= elapsed + AHEAD + 0.25 and ended[0]["seconds"] < 10


def test_a_server_runs_a_bounded_number_of_microphones(base, monkeypatch):
    import mpeg4fa.serve.microphone as microphone

    monkeypatch.setattr(microphone, "MAX_SESSIONS", 1)
    chunk = np.zeros(CHUNK, np.int16).tobytes()
    with connect(ws_url(base), origin=base) as first, connect(ws_url(base), origin=base) as second:
        json.loads(first.recv(timeout=10)), json.loads(second.recv(timeout=10))
        first.send(pack(MIC_KIND, 0.0, chunk))
        assert json.loads(first.recv(timeout=20))["state"] == "started"
        second.send(pack(MIC_KIND, 0.0, chunk))
        answer = json.loads(second.recv(timeout=10))
        assert answer["type"] == "error" and answer["where"] == "mic" and "already" in answer["error"]
        first.send(pack(MIC_KIND, 0.02, b""))
        assert receive_all(first, until="ended")[0][-1]["state"] == "ended"
        second.send(pack(MIC_KIND, 0.0, chunk))  # one stopped: the other may start
        assert json.loads(second.recv(timeout=20))["state"] == "started"
    time.sleep(0.5)  # the closed connections' sessions end
    assert microphone.Microphone.running == 0


def feed_with_clock(pcm: np.ndarray, read_at, *, listen: bool = True) -> tuple[list[dict], int, list[bool]]:
    """Feed ``pcm`` in 20 ms chunks to a Microphone whose clock reads ``read_at(k)`` when chunk ``k`` is
    taken (when the server gets to it): the messages it sent, the frames of its faces, and which chunks it
    skipped. ``listen=False`` leaves the listener out (its decision alone, for long sessions: the listener
    hears 20 ms in 4-8 ms on these cores)."""
    import asyncio

    from mpeg4fa.serve.microphone import Microphone

    texts, frames, skips = [], [0], []

    async def send(message) -> None:
        if isinstance(message, dict):
            texts.append(message)
        else:
            frames[0] += len(decode(unpack(message)[2]).timestamps)

    class Deaf:  # skips and hears nothing (the decision is the Microphone's)
        latency, frames_out, skipped = LATENCY, 0, 0

        def skip(self, samples):
            self.skipped += len(samples)
            return np.zeros((0, 68))

        def feed(self, samples):
            return np.zeros((0, 68))

        def flush(self):
            return np.zeros((0, 68))

    async def main() -> None:
        k = [0]
        mic = Microphone(send, FPS, clock=lambda: read_at(k[0]))
        real_feed = mic._feed

        def feed(live, coder, samples, skip=False):
            if samples is not None:
                skips.append(skip)
            return real_feed(live, coder, samples, skip)

        mic._feed = feed
        if not listen:
            mic._ready = lambda fps: (Deaf(), None)
        for k[0], i in enumerate(range(0, len(pcm), CHUNK)):
            await mic.take(pack(MIC_KIND, i / RATE, pcm[i:i + CHUNK].astype("<i2").tobytes()))
        await mic.take(pack(MIC_KIND, len(pcm) / RATE, b""))
        await mic.close()

    asyncio.run(main())
    return texts, frames[0], skips


def stalled(at: int, stall: float, read: float = 0.005):
    """A server clock: chunk ``at`` is taken ``stall`` s late; the backlog is then read ``read`` s a chunk."""
    def read_at(k: int) -> float:
        on_time = (k + 1) * CHUNK / RATE
        if k < at:
            return on_time
        return max(on_time, at * CHUNK / RATE + stall + (k - at) * read)
    return read_at


@pytest.mark.parametrize("stall, seconds, listen", [(3.007, 11, True), (12.007, 40, False)],
                         ids=["3 s", "12 s, past the baseline's window once"])
def test_a_server_that_falls_behind_skips_to_catch_up(stall, seconds, listen):
    """A server stalled (a busy machine) finds the chunks queued: the ones more than MAX_BEHIND late are
    skipped until one comes within CAUGHT_UP, the page is told when it begins and when listening resumes,
    and every frame still comes, in order. Before, the face stayed the stall behind the voice for the rest of
    the session; and the baseline's window, kept in wall-clock time, forgot the lateness before a stall longer
    than itself (12 s: nothing was skipped). Off the 20 ms grid: no lateness falls on a bound."""
    from mpeg4fa.serve.microphone import CAUGHT_UP, MAX_BEHIND

    pcm = np.tile(speech_pcm()[0], 11)[:seconds * RATE]
    read_at = stalled(50, stall)
    texts, frames, skips = feed_with_clock(pcm, read_at, listen=listen)
    states = [m.get("state") for m in texts]
    assert states == ["started", "skipping", "resumed", "ended"], texts
    skipped = texts[-1]["skipped"]
    assert texts[2]["skipped"] == pytest.approx(skipped)
    # skipped: the chunks taken more than MAX_BEHIND late, until one was within CAUGHT_UP
    late = np.array([read_at(k) - (k + 1) * CHUNK / RATE for k in range(len(skips))])
    first = int(np.argmax(late > MAX_BEHIND))
    last = first + int(np.argmax(late[first:] <= CAUGHT_UP))
    assert np.flatnonzero(skips).tolist() == list(range(first, last))
    assert skipped == pytest.approx((last - first) * CHUNK / RATE)
    assert texts[1]["at"] == pytest.approx(first * CHUNK / RATE) and texts[2]["at"] == pytest.approx(last * CHUNK / RATE)
    if listen:
        assert frames == texts[-1]["frames"] == math.ceil(len(pcm) / RATE * FPS)


@pytest.mark.parametrize("rate", [0.98, 0.90])
def test_a_slow_sound_clock_skips_nothing_a_slow_server_is_caught_up(rate):
    """Chunks that come slower than the server's clock: a page's sound clock running slow (Chromium's fake
    microphone on a busy machine ran 1.5 % slow) and a server slower than real time look alike. Within the
    baseline's 60 s of audio, 2 % is taken for the clock (1.8 s late after 90 s: nothing skipped) and 10 %
    for the server: it skips from the chunk MAX_BEHIND late on (here the chunks keep coming slow, so to the
    end; a server that skips reads its backlog at once and resumes, as above)."""
    from mpeg4fa.serve.microphone import MAX_BEHIND

    n = 90 * RATE // CHUNK
    texts, _, skipped = feed_with_clock(np.zeros(n * CHUNK), lambda k: (k + 1) * CHUNK / RATE / rate, listen=False)
    late = np.arange(n) * CHUNK / RATE * (1 / rate - 1)  # each chunk's lateness against the first's
    assert late[-1] > MAX_BEHIND and len(skipped) == n
    if rate > 0.975:
        assert not any(skipped) and [m["state"] for m in texts] == ["started", "ended"]
    else:
        first = int(np.argmax(late > MAX_BEHIND))
        assert np.flatnonzero(skipped).tolist() == list(range(first, n)), (first, np.flatnonzero(skipped)[:3])
        assert [m["state"] for m in texts] == ["started", "skipping", "ended"]
        assert texts[-1]["skipped"] == pytest.approx((n - first) * CHUNK / RATE)


def test_without_the_align_extra_serve_starts_and_the_microphone_says_so(monkeypatch):
    """The listener needs pocketsphinx (the 'align' extra), serve only the 'web' one: without it, serve's
    warm-up builds nothing (it built a listener and failed, so serve did not start) and a microphone session
    answers with one error naming the extra, no traceback."""
    import asyncio

    from mpeg4fa import extras
    from mpeg4fa.serve.microphone import Microphone

    installed = extras._installed
    monkeypatch.setattr(extras, "_installed", lambda module: module != "pocketsphinx" and installed(module))
    Microphone.warm_up(24.0)
    assert 24.0 not in Microphone.spare
    texts = []

    async def send(message) -> None:
        texts.append(message)

    async def main() -> None:
        mic = Microphone(send, 24.0)
        await mic.take(pack(MIC_KIND, 0.0, np.zeros(CHUNK, "<i2").tobytes()))
        assert mic.live is None and Microphone.running == 0
        await mic.close()

    asyncio.run(main())
    assert len(texts) == 1 and texts[0]["type"] == "error" and texts[0]["where"] == "mic", texts
    assert "'align' extra" in texts[0]["error"] and "pip install 'mpeg4fa[align]'" in texts[0]["error"]
