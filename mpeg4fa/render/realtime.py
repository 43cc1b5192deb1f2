"""Live playback: pace a stream of timestamped items to the wall clock.

Items (decoded FAP frames from a network stream, say) arrive from a source
iterable, each with a presentation timestamp in seconds. :func:`live` turns the
items that are still on time into images with a render callable and yields them
when they are due.

Pacing policy
-------------
* **One anchor, never moved.** The schedule is anchored on the first item: the
  anchor is the clock reading when that item has arrived and been rendered
  (so a slow first render, a shader compile say, is start-up latency and does
  not make the next frames stale). An item stamped ``t`` is due at
  ``anchor + (t - t_first)``. Being late never re-anchors the schedule, so
  drift cannot build up: the loop catches up by dropping frames, not by showing
  everything later.
* **Render ahead, present on time.** An item is rendered as soon as the loop gets
  to it, then held (``sleep``) until it is due and only then yielded, so with a
  renderer that keeps up every frame is shown at its due time.
* **Drop what would be stale.** Before rendering, the loop predicts when the
  frame would be shown: now plus the typical render cost (median of the last few
  renders). If that is more than ``late_tolerance`` past due *and a newer item is
  already at hand*, the item is dropped unrendered. If nothing newer has arrived
  the late item is rendered anyway: a late frame beats a frozen window, the loop
  always makes progress even when one render takes longer than the tolerance,
  and the last frame of a stream (the closing pose) is never lost. Lateness so
  stays within about one tolerance plus one render and does not accumulate.
* ``late_tolerance`` defaults to one frame period, estimated from the
  timestamps (median spacing); 40 ms until two items have been seen.
* **Background reader.** The source is iterated in a daemon thread into a
  bounded queue: a slow source does not stall rendering, a fast one does not
  grow memory. Its exceptions reach the consumer unchanged (after the frames
  decoded before the fault), a source silent for ``stall_timeout`` seconds of
  real time raises :class:`RenderError`, and closing the generator stops the
  thread.
"""
from __future__ import annotations

import math
import queue
import statistics
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from inspect import isgenerator
from typing import Any, Generic, TypeVar

from mpeg4fa.render.errors import RenderError

__all__ = ["LiveFrame", "LiveStats", "live"]

T = TypeVar("T")
R = TypeVar("R")

DEFAULT_TOLERANCE = 0.040  # s: one 25 fps frame, used until the period is known
_PERIOD_WINDOW = 16  # timestamp spacings kept for the period estimate
_COST_WINDOW = 9  # render durations kept for the cost estimate (median: one slow render is an outlier)
_PEEK_GRACE = 0.002  # s of real time a producer with items ready gets to hand the next one over
_PUT_POLL = 0.05  # s: how often a producer blocked on a full queue looks at the stop event
_JOIN_WAIT = 0.25  # s: how long closing waits for the reader thread
_SLEEP_TRIES = 4  # re-sleeps when the sleep function wakes early
THREAD_NAME = "mpeg4fa-live-source"

_ITEM, _END, _FAIL = "item", "end", "fail"


@dataclass(frozen=True)
class LiveFrame(Generic[T, R]):
    """One shown frame. Times are seconds on the loop's clock, relative to the anchor."""

    index: int  # index of the item in the source (dropped items count too)
    timestamp: float  # the item's presentation timestamp
    shown_at: float  # when it was yielded
    lateness: float  # shown_at - due, never negative
    image: R  # what render returned
    item: T  # the source item
    due: float  # when it should have been shown


@dataclass
class LiveStats:
    """Running totals of a live session, updated as it plays; read them at the end."""

    received: int = 0  # items taken from the source
    rendered: int = 0  # items rendered and yielded
    dropped: int = 0  # items skipped because they would have been shown too late
    max_lateness: float = 0.0  # s, worst lateness of a shown frame
    total_lateness: float = 0.0  # s, summed over shown frames
    stalls: int = 0  # the source went silent for stall_timeout (fatal, so 0 or 1)
    underruns: int = 0  # the loop waited for the source and the item came in already late
    render_seconds: float = 0.0  # time spent inside render
    period: float | None = None  # estimated frame period from the timestamps

    @property
    def mean_lateness(self) -> float:
        return self.total_lateness / self.rendered if self.rendered else 0.0

    @property
    def drop_rate(self) -> float:
        return self.dropped / self.received if self.received else 0.0

    def summary(self) -> str:
        """One line for a log or the end of a CLI run."""
        return (
            f"{self.rendered} shown, {self.dropped} dropped of {self.received}; "
            f"lateness mean {self.mean_lateness * 1e3:.1f} ms, max {self.max_lateness * 1e3:.1f} ms; "
            f"{self.underruns} underruns, {self.stalls} stalls"
        )


def live(
    source: Iterable[T],
    render: Callable[[T], R],
    *,
    timestamp: Callable[[T], float],
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
    stall_timeout: float = 2.0,
    late_tolerance: float | None = None,
    queue_size: int = 8,
    stats: LiveStats | None = None,
) -> Iterator[LiveFrame[T, R]]:
    """Render and yield the source's items at their presentation times, dropping stale ones.

    ``clock`` and ``sleep`` pace the schedule (inject a fake pair to test it);
    ``stall_timeout`` is real time, since it guards against a dead source.
    Pass ``stats`` to read the totals during or after playback. Close the
    returned generator (or ``break`` out and drop it) to stop the reader thread.
    """
    if not stall_timeout > 0:
        raise ValueError(f"stall_timeout must be > 0 s, not {stall_timeout!r}")
    if late_tolerance is not None and not late_tolerance >= 0:
        raise ValueError(f"late_tolerance must be >= 0 s, not {late_tolerance!r}")
    if queue_size < 1:
        raise ValueError(f"queue_size must be >= 1, not {queue_size!r}")
    return _play(
        source, render, timestamp, clock, sleep, float(stall_timeout), late_tolerance, int(queue_size),
        stats if stats is not None else LiveStats(),
    )


def _play(
    source: Iterable[T],
    render: Callable[[T], R],
    timestamp: Callable[[T], float],
    clock: Callable[[], float],
    sleep: Callable[[float], None],
    stall_timeout: float,
    late_tolerance: float | None,
    queue_size: int,
    stats: LiveStats,
) -> Iterator[LiveFrame[T, R]]:
    feed = _Feed(source, queue_size)
    stalled = False
    try:
        anchor = first_t = previous_t = 0.0
        spacings: deque[float] = deque(maxlen=_PERIOD_WINDOW)
        costs: deque[float] = deque(maxlen=_COST_WINDOW)
        index = -1
        while True:
            message = feed.take(stall_timeout)
            if message is None:
                stalled = True
                stats.stalls += 1
                raise RenderError(
                    f"source stalled: no frame for {stall_timeout:g} s",
                    where="live source",
                    hint="check the stream or connection, or raise stall_timeout for a source slow to start",
                )
            kind, item, waited = message
            if kind == _END:
                return
            if kind == _FAIL:
                item.add_note(f"raised by the live source's reader thread after {index + 1} items")
                raise item

            index += 1
            stats.received += 1
            t = float(timestamp(item))
            if not math.isfinite(t):
                raise RenderError(f"timestamp {t!r} of item {index} is not finite", where=f"live source item {index}")
            now = clock()
            if index == 0:
                first_t = t
            elif t < previous_t:
                raise RenderError(
                    f"timestamp goes backwards at item {index}: {t:g} s after {previous_t:g} s",
                    where=f"live source item {index}",
                    hint="the source must deliver items in presentation order",
                )
            elif t > previous_t:
                spacings.append(t - previous_t)
                stats.period = statistics.median(spacings)
            previous_t = t

            due = t - first_t
            if index > 0:
                tolerance = late_tolerance if late_tolerance is not None else (stats.period or DEFAULT_TOLERANCE)
                if waited and now - anchor > due + tolerance:
                    stats.underruns += 1
                cost = statistics.median(costs) if costs else 0.0
                if now - anchor + cost - due > tolerance and feed.newer_ready():
                    stats.dropped += 1
                    continue

            started = clock()
            image = render(item)
            spent = clock() - started
            stats.render_seconds += spent
            if index == 0:
                anchor = started + spent  # the first frame is due the moment it is ready
            else:  # the first render (warm-up) says little about the next ones
                costs.append(spent)

            for _ in range(_SLEEP_TRIES):
                ahead = due - (clock() - anchor)
                if ahead <= 0:
                    break
                sleep(ahead)
            shown_at = clock() - anchor
            lateness = max(0.0, shown_at - due)
            stats.rendered += 1
            stats.total_lateness += lateness
            stats.max_lateness = max(stats.max_lateness, lateness)
            yield LiveFrame(index, t, shown_at, lateness, image, item, due)
    finally:
        feed.close(wait=not stalled)  # a stalled reader is stuck inside the source: no use waiting


class _Feed:
    """The source read in a daemon thread into a bounded queue, with one item of look-ahead."""

    def __init__(self, source: Iterable[Any], size: int) -> None:
        self._queue: queue.Queue[tuple[str, Any]] = queue.Queue(maxsize=size)
        self._stop = threading.Event()
        self._ahead: deque[tuple[str, Any]] = deque()
        self.thread = threading.Thread(target=self._produce, args=(source,), name=THREAD_NAME, daemon=True)
        self.thread.start()

    def _produce(self, source: Iterable[Any]) -> None:
        iterator = None
        try:
            iterator = iter(source)
            while not self._stop.is_set():
                try:
                    item = next(iterator)
                except StopIteration:
                    self._put((_END, None))
                    return
                if not self._put((_ITEM, item)):
                    return
        except BaseException as exc:  # handed to the consumer, which re-raises it
            self._put((_FAIL, exc))
        finally:
            # Stopped early: let a generator source release what it holds (sockets, files).
            if self._stop.is_set() and isgenerator(iterator):
                try:
                    iterator.close()
                except Exception:
                    pass

    def _put(self, message: tuple[str, Any]) -> bool:
        # A plain blocking put could hang forever on a full queue once the consumer is gone.
        while not self._stop.is_set():
            try:
                self._queue.put(message, timeout=_PUT_POLL)
                return True
            except queue.Full:
                continue
        return False

    def take(self, timeout: float) -> tuple[str, Any, bool] | None:
        """The next message and whether the loop had to wait for it; None after ``timeout`` s of silence."""
        if self._ahead:
            kind, value = self._ahead.popleft()
            return kind, value, False
        try:
            kind, value = self._queue.get_nowait()
            return kind, value, False
        except queue.Empty:
            pass
        try:
            kind, value = self._queue.get(timeout=timeout)
            return kind, value, True
        except queue.Empty:
            return None

    def newer_ready(self) -> bool:
        """Whether another item is already at hand (waiting a moment for a producer that has one)."""
        if not self._ahead:
            try:
                self._ahead.append(self._queue.get(timeout=_PEEK_GRACE))
            except queue.Empty:
                return False
        return self._ahead[0][0] == _ITEM

    def close(self, wait: bool = True) -> None:
        self._stop.set()
        self._ahead.clear()
        try:  # make room so a producer blocked on put sees the stop event at once
            while True:
                self._queue.get_nowait()
        except queue.Empty:
            pass
        if wait and self.thread is not threading.current_thread():
            self.thread.join(timeout=_JOIN_WAIT)
