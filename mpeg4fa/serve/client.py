"""A Python client of the live protocol that plays what it receives on a clock, at any speed.

It does what the browser page does, without the pictures: it keeps what has come (each sentence's
FBA bitstream decoded by :func:`mpeg4fa.fba.decode`, as the page decodes it with fba.js), plays it on a
clock that starts ``prebuffer`` seconds (media) after the first frame and runs ``speed`` times real
time, reports its buffer every ``report_every`` seconds of real time, and counts *underruns*:
frames or audio that arrive after their media time has already been played. ``speed > 1`` plays
a long speech in less time: the server paces by the client's reports only, so it cannot tell.
Used by the tests and ``tools/bench_serve.py``. It sends the server's own origin (:func:`origin`) on
the handshake, as the server's page does: the server refuses a WebSocket without one
(:mod:`mpeg4fa.guard`).
"""
from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from urllib.parse import urlsplit

import numpy as np

from mpeg4fa.fba import decode
from mpeg4fa.serve.protocol import AUDIO_KIND, FBA_KIND, unpack


@dataclass
class Played:
    hello: dict
    first_frame_after: float | None = None  # s of real time from sending say to the first FBA message
    frames: int = 0
    times: list[float] = field(default_factory=list)  # media times of the decoded frames
    values: list[np.ndarray] = field(default_factory=list)  # per segment: its decoded (frames, 68) FAP values
    segments: list[dict] = field(default_factory=list)  # segment messages, each with its "fba" bytes added
    face_bytes: int = 0  # bytes of the binary FBA messages (head included): the face data received
    audio: list[tuple[float, bytes]] = field(default_factory=list)
    underruns: int = 0  # items that came after the playhead had passed their time
    max_lateness: float = 0.0  # s of media by which the latest of them was late
    max_ahead: float = 0.0  # s of audio the client held beyond its playhead, at most (the window paces it)
    max_face_ahead: float = 0.0  # s of face frames held beyond the playhead, at most (a sentence's go out whole)
    min_margin: float = float("inf")  # s of media by which an item came before its time, at least (< 0: late)
    errors: list[dict] = field(default_factory=list)
    done: dict | None = None
    wall: float = 0.0  # s of real time from say to done
    reports: int = 0

    @property
    def audio_seconds(self) -> float:
        rate = self.segments[0]["rate"] if self.segments else 1
        return sum(len(b) for _, b in self.audio) / 2 / rate


def origin(url: str) -> str:
    """The web origin of the server at ``url`` (``ws://127.0.0.1:8766/ws`` -> ``http://127.0.0.1:8766``): what its
    own page sends as ``Origin``, and so what a client outside a browser sends to be let in."""
    parts = urlsplit(url)
    return f"{'https' if parts.scheme in ('wss', 'https') else 'http'}://{parts.netloc}"


def play(url: str, text: str, *, speed: float = 1.0, prebuffer: float = 0.3, report_every: float = 0.1,
         timeout: float = 120.0, say: dict | None = None) -> Played:
    """Say ``text`` on the server at ``url`` (``ws://host:port/ws``) and play the answer to its end."""
    from websockets.sync.client import connect

    with connect(url, max_size=None, open_timeout=10, origin=origin(url)) as ws:
        result = Played(hello=json.loads(ws.recv(timeout=10)))
        t_say = time.monotonic()
        ws.send(json.dumps({"type": "say", "text": text, **(say or {})}))
        play_start = None  # real time at which media time 0 plays
        received = 0.0
        next_report = t_say
        pending_segment: dict | None = None
        deadline = t_say + timeout

        def playhead(now: float) -> float:
            return 0.0 if play_start is None else max(0.0, (now - play_start) * speed)

        def arrived(t: float, end: float, now: float, face: bool = False) -> None:
            nonlocal received
            head = playhead(now)
            if play_start is not None and now >= play_start:
                result.min_margin = min(result.min_margin, t - head)
            if play_start is not None and t < head:
                result.underruns += 1
                result.max_lateness = max(result.max_lateness, head - t)
            received = max(received, end)
            if face:
                result.max_face_ahead = max(result.max_face_ahead, end - head)
            else:
                result.max_ahead = max(result.max_ahead, end - head)

        while result.done is None:
            now = time.monotonic()
            if now > deadline:
                raise TimeoutError(f"no done within {timeout:g} s")
            if now >= next_report:
                ws.send(json.dumps({"type": "buffer", "received": received,
                                    "buffered": max(0.0, received - playhead(now))}))
                result.reports += 1
                next_report = now + report_every
            try:
                message = ws.recv(timeout=max(0.001, next_report - time.monotonic()))
            except TimeoutError:
                continue
            now = time.monotonic()
            if isinstance(message, bytes):
                kind, t, payload = unpack(message)
                if kind == FBA_KIND:
                    result.face_bytes += len(message)
                    stream = decode(payload)
                    if result.first_frame_after is None:
                        result.first_frame_after = now - t_say
                        play_start = now + prebuffer / speed
                    times = (t + np.asarray(stream.timestamps, np.float64)).tolist()
                    if times:
                        arrived(times[0], times[-1] + 1.0 / result.hello["fps"], now, face=True)
                    result.times += times
                    result.values.append(stream.fap_values.copy())
                    result.frames += len(times)
                    if pending_segment is not None:
                        pending_segment["fba"] = payload
                        result.segments.append(pending_segment)
                        pending_segment = None
                elif kind == AUDIO_KIND:
                    rate = result.segments[-1]["rate"]
                    arrived(t, t + len(payload) / 2 / rate, now)
                    result.audio.append((t, payload))
                continue
            data = json.loads(message)
            kind = data.get("type")
            if kind == "segment":
                pending_segment = data
            elif kind == "error":
                result.errors.append(data)
                if data.get("where") not in ("busy",):
                    break
            elif kind == "done":
                result.done = data
        result.wall = time.monotonic() - t_say
        return result


def audio_samples(played: Played) -> np.ndarray:
    """All audio received, in order, as one int16 array."""
    return np.concatenate([np.frombuffer(b, "<i2") for _, b in played.audio]) if played.audio else np.zeros(0, "<i2")
