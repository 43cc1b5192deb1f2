"""The microphone of ``mpeg4fa serve``: the page's audio in, the face's frames out while the person speaks.

The page (``static/js/mic.js``) captures the microphone with ``getUserMedia``, downsamples it to
16 kHz in an AudioWorklet (``static/js/mic-worklet.js``) and sends it over ``/ws`` in binary messages
with the head the server's own binary messages have (:func:`mpeg4fa.serve.protocol.pack`):

``MIC1`` + float64 media time of the chunk's first sample (s from the start of the session) + s16le mono PCM at 16 kHz
    The first chunk starts a session (its time is the session's origin); an empty one ends it. A
    session no chunk reaches for :data:`IDLE_END` s ends by itself (the next chunk starts another, from
    its own time). A chunk that starts after the audio received so far (the page dropped some) has the
    gap filled with silence, up to :data:`MAX_GAP` s.

The server runs :class:`mpeg4fa.speech.live.LiveLipSync` on it and answers on the same socket with the
face as the text path sends it (:mod:`.protocol`): ``FBA1`` binary messages, each a complete fba_object
(:class:`~mpeg4fa.speech.live.LiveEncoder`) whose media time is the session time of the audio its first
frame shows; a frame goes out as soon as the audio ``latency`` s after it has come. The page hands
them to the player's own handler (``window.player.onBinary``), which decodes and plays them like a
sentence's stream. Text messages:

``{"type": "mic", "state": "started", "latency": 0.18, "rate": 16000, "fps": 25.0}``
``{"type": "mic", "state": "ended", "frames": n, "seconds": s, "skipped": s}``
``{"type": "mic", "state": "skipping", "at": t}`` and ``{"type": "mic", "state": "resumed", "at": t, "skipped": s}``

Falling behind: recognition runs chunk by chunk, and a machine too busy to keep up would leave the
face further behind the voice for the rest of the session (the chunks wait in the socket). So each
chunk's lateness is measured, the wall-clock time since the session began less the audio time its end
reaches, against the least lateness over the last :data:`BASELINE_SECONDS` of audio (the page's sound
clock and this one may drift apart; a chunk that came at once sets the baseline; the window is of audio,
so a stall of any length is measured against the lateness before it). Past :data:`MAX_BEHIND` s the
listener skips chunks (:meth:`~mpeg4fa.speech.live.LiveLipSync.skip`: the mouth rests over them) until
one comes within :data:`CAUGHT_UP` s of the baseline; the page is told when skipping begins and when it
resumes listening (``at``: the media time; ``skipped``: the seconds skipped so far), and ``ended`` says
how many seconds were skipped in all. A session's listener is built ahead (:meth:`Microphone.warm_up`,
on ``serve``'s start and, in the background, when a session ends), so the first chunk is heard at once.

Guard (as :mod:`mpeg4fa.guard` bounds HTTP bodies and :mod:`.protocol` the JSON messages): a chunk
holds at most :data:`MAX_CHUNK_SECONDS` of audio and an even number of bytes; a session's audio may
not run ahead of the wall clock since it began by more than :data:`AHEAD` s (the page sends in real
time; a client pushing faster would make the server listen faster than anyone speaks); at most
:data:`MAX_SESSIONS` sessions run at once in a server. A chunk outside these is dropped with an
``error`` (``where``: ``mic``), and the session goes on.
"""
from __future__ import annotations

import asyncio
import collections
import contextlib
import threading
import time

import numpy as np

from mpeg4fa.serve.protocol import FBA_KIND, error_message, pack, unpack
from mpeg4fa.spec import N_FAPS

MIC_KIND = b"MIC1"
RATE = 16000
"""The sample rate the page sends (the recogniser's)."""
MAX_CHUNK_SECONDS = 0.25
MAX_CHUNK_BYTES = int(MAX_CHUNK_SECONDS * RATE) * 2
AHEAD = 1.0
"""Seconds of audio a session may hold beyond the wall-clock time since its first chunk."""
MAX_GAP = 1.0
"""The longest gap between chunks filled with silence; a chunk later than that is dropped."""
IDLE_END = 5.0
"""Seconds without a chunk after which a session ends by itself."""
MAX_BEHIND = 1.5
"""Seconds a chunk may come later than the baseline before the listener skips audio to catch up. Less is
caught up by listening faster than real time (2.5x on 2 cores, ``tools/bench_live.py``'s fast mode): with
Chromium drawing beside it and a busy loop on the other core, a session's chunks came up to 1.2 s late and
were all heard."""
CAUGHT_UP = 0.1
"""Seconds within the baseline at which skipping stops."""
BASELINE_SECONDS = 60.0
"""The window (s of audio) whose least lateness is the baseline. A server slower than real time and a sound
clock slower than this one look alike (lateness that grows); within the window, growth past MAX_BEHIND is
taken for the server's: a sound clock may run up to 2.5 % slow (Chromium's fake microphone on a busy
machine ran 1.5 % slow), a server falling 2.5 % or more behind real time is caught up."""
MAX_SESSIONS = 4
"""Sessions one server runs at once: each holds four phone decoders, about 115 MiB (and one more is kept
built ahead for the next session)."""


def _listener(fps: float):
    """A session's listener: the bundled phone loop at :data:`RATE`, with blinks and head motion."""
    from mpeg4fa.speech.live import LiveLipSync

    return LiveLipSync(RATE, fps, idle=True)


def is_microphone(data: bytes | None) -> bool:
    """Whether a binary client message is microphone audio (the rest go to :func:`.protocol.parse_client`)."""
    return data is not None and data[:4] == MIC_KIND


class Microphone:
    """One connection's microphone: sessions of :class:`~mpeg4fa.speech.live.LiveLipSync`, one at a time.

    ``send``: the connection's sender (JSON dicts and bytes). Recognition and coding run in a worker
    thread, chunk by chunk in order (the connection reads its next message only when a chunk is done).
    """

    running = 0  # sessions live in this process (one server per process; tests run theirs one at a time)

    def __init__(self, send, fps: float, clock=time.monotonic) -> None:
        self.send, self.fps, self.clock = send, float(fps), clock
        self.live = None
        self.coder = None
        self.started_at = 0.0
        self.received = 0  # samples of this session
        self.frames = 0
        self.last_chunk = 0.0
        self.watchdog: asyncio.Task | None = None
        self.origin = 0.0  # the session's first chunk's media time
        self.tasks: set[asyncio.Task] = set()  # watchdogs running (the loop holds tasks only weakly)
        self.busy = asyncio.Lock()  # one LiveLipSync call at a time (a chunk, or the watchdog's end)
        self.late = collections.deque()  # (audio time, lateness) of the chunks of the last BASELINE_SECONDS
        self.skipping = False

    async def take(self, data: bytes) -> None:
        """One ``MIC1`` message."""
        try:
            _, t, payload = unpack(data)
        except ValueError as exc:
            await self.send(error_message(str(exc), "mic"))
            return
        if len(payload) % 2 or len(payload) > MAX_CHUNK_BYTES:
            await self.send(error_message(f"a microphone chunk is s16le PCM of at most {MAX_CHUNK_BYTES} bytes "
                                          f"({MAX_CHUNK_SECONDS:g} s at {RATE} Hz), not {len(payload)}", "mic"))
            return
        if not payload:
            await self.end()
            return
        if self.live is None:
            if Microphone.running >= MAX_SESSIONS:
                await self.send(error_message(f"{MAX_SESSIONS} microphones are live on this server already: "
                                              "try again when one has stopped", "mic"))
                return
            if not await self.start(t if np.isfinite(t) else 0.0):
                return
        now = self.clock()
        self.last_chunk = now
        ahead = (t - self.origin) * RATE - self.received if np.isfinite(t) else 0.0  # float first: t may be 1e308
        if not np.isfinite(ahead) or ahead > MAX_GAP * RATE or ahead < -(len(payload) // 2):
            await self.send(error_message(f"a chunk at {t:.6g} s, the audio so far ends at "
                                          f"{self.origin + self.received / RATE:.6g} s: chunks come in order, gaps "
                                          f"under {MAX_GAP:g} s", "mic"))
            return
        gap = int(round(ahead))
        samples = np.frombuffer(payload, "<i2")
        if gap > 0:
            samples = np.concatenate([np.zeros(gap, np.int16), samples])
        elif gap < 0:  # overlaps what came: keep the new part
            samples = samples[-gap:]
        if (self.received + len(samples)) / RATE > now - self.started_at + AHEAD:
            await self.send(error_message(f"microphone audio faster than real time: {self.received / RATE:.2f} s "
                                          f"in {now - self.started_at:.2f} s (at most {AHEAD:g} s ahead)", "mic"))
            return
        self.received += len(samples)
        skip = self._behind(now)
        if skip != self.skipping:  # the page shows the skipped time as the server's, not the microphone's
            at = self.origin + (self.received - len(samples)) / RATE
            await self.send({"type": "mic", "state": "skipping", "at": at} if skip else
                            {"type": "mic", "state": "resumed", "at": at,
                             "skipped": self.live.skipped / RATE if self.live is not None else 0.0})
        self.skipping = skip
        async with self.busy:
            if self.live is not None:
                await self._out(await asyncio.to_thread(self._feed, self.live, self.coder, samples, skip))

    def _behind(self, now: float) -> bool:
        """Whether the chunk whose audio ends the session's (``received``) is to be skipped: it came more
        than MAX_BEHIND s later than the baseline, or skipping goes on and it is not within CAUGHT_UP."""
        audio = self.received / RATE
        late = (now - self.started_at) - audio
        while self.late and self.late[0][0] < audio - BASELINE_SECONDS:
            self.late.popleft()
        while self.late and self.late[-1][1] >= late:  # the least of the window stays first
            self.late.pop()
        self.late.append((audio, late))
        behind = late - self.late[0][1]
        return behind > (CAUGHT_UP if self.skipping else MAX_BEHIND)

    @staticmethod
    def _feed(live, coder, samples: np.ndarray | None, skip: bool = False) -> tuple[int, int, bytes | None]:
        """In the worker thread: the frames that came due (all the rest when ``samples`` is None), coded:
        (the first one's number, how many, the fba_object). ``skip``: the audio is passed over."""
        first = live.frames_out
        frames = live.flush() if samples is None else live.skip(samples) if skip else live.feed(samples)
        return first, len(frames), coder.encode(frames) if len(frames) else None

    async def start(self, origin: float) -> bool:
        """Begin a session at the first chunk (False, with an error sent, when the microphone cannot run)."""
        from mpeg4fa.extras import absent

        missing = absent("align", "pocketsphinx")
        if missing is not None:
            await self.send(error_message(str(missing), "mic"))
            return False
        self.started_at = self.last_chunk = self.clock()  # the first chunk's arrival: the audio's clock
        Microphone.running += 1
        try:
            self.live, self.coder = await asyncio.to_thread(self._ready, self.fps)
        except BaseException:
            Microphone.running -= 1
            raise
        self.received = self.frames = 0
        self.late.clear()
        self.late.append((0.0, 0.0))  # the first chunk came at once: the chunks queued meanwhile are late
        self.skipping = False
        self.origin = origin
        self.watchdog = asyncio.create_task(self._watch())
        self.tasks.add(self.watchdog)
        self.watchdog.add_done_callback(self.tasks.discard)
        await self.send({"type": "mic", "state": "started", "latency": self.live.latency, "rate": RATE,
                         "fps": self.fps})
        return True

    spare: dict[float, object] = {}  # fps -> a listener built ahead (a LiveLipSync, 115 MiB), for the next session
    building: set[float] = set()  # fps whose spare is being built
    spare_lock = threading.Lock()

    @staticmethod
    def warm_up(fps: float) -> None:
        """Build the next session's listener and load the coding's compiled code ahead (nothing without the
        ``align`` extra: a session then says it is missing). Why: a listener takes 0.45 s to build (its four
        decoders load their models; 1.3 s with Chromium drawing beside it) and the first fba_object 0.8 s,
        while the session's audio queues; the face would start that far behind the voice and skip to catch
        up. ``serve`` calls it on starting; a session's end builds the next in the background."""
        from mpeg4fa.extras import absent
        from mpeg4fa.speech.live import LiveEncoder

        if absent("align", "pocketsphinx") is not None:
            return
        with Microphone.spare_lock:
            if fps in Microphone.spare or fps in Microphone.building:
                return
            Microphone.building.add(fps)
        try:
            LiveEncoder(fps).encode(np.zeros((1, N_FAPS)))
            live = _listener(fps)
            with Microphone.spare_lock:
                Microphone.spare.setdefault(fps, live)
        finally:
            with Microphone.spare_lock:
                Microphone.building.discard(fps)

    @staticmethod
    def build_ahead(fps: float) -> None:
        """:meth:`warm_up` in a thread of its own: the connection goes on reading meanwhile (a session
        started before it is done builds its own listener)."""
        def build() -> None:
            with contextlib.suppress(Exception):  # a spare that fails to build is built again by its session
                Microphone.warm_up(fps)

        # not a daemon: the interpreter waits for it (a second at most) rather than stop it inside pocketsphinx
        threading.Thread(target=build, name="microphone-spare").start()

    @staticmethod
    def _ready(fps: float):
        """In the worker thread: the session's listener (the one built ahead, if any) and its coder."""
        from mpeg4fa.speech.live import LiveEncoder

        with Microphone.spare_lock:
            live = Microphone.spare.pop(fps, None)
        return live if live is not None else _listener(fps), LiveEncoder(fps)

    async def end(self) -> None:
        """Flush the session's last frames and say it ended (nothing when none runs)."""
        live, self.live = self.live, None
        if live is None:
            return
        Microphone.running -= 1
        watchdog, self.watchdog = self.watchdog, None
        if watchdog is not None and watchdog is not asyncio.current_task():
            watchdog.cancel()
        async with self.busy:
            await self._out(await asyncio.to_thread(self._feed, live, self.coder, None))
        await self.send({"type": "mic", "state": "ended", "frames": self.frames, "seconds": self.received / RATE,
                         "skipped": live.skipped / RATE})
        self.build_ahead(self.fps)

    async def close(self) -> None:
        """The connection is gone: stop the watchdog (no frames to send)."""
        if self.live is not None:
            Microphone.running -= 1
            self.build_ahead(self.fps)
        self.live = None
        for task in list(self.tasks):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task

    async def _watch(self) -> None:
        while self.live is not None:
            left = self.last_chunk + IDLE_END - self.clock()
            if left <= 0:
                await self.end()
                return
            await asyncio.sleep(left)

    async def _out(self, coded: tuple[int, int, bytes | None]) -> None:
        first, n, data = coded
        if data is None:
            return
        self.frames = first + n
        await self.send(pack(FBA_KIND, self.origin + first / self.fps, data))
