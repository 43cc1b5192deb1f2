"""Flow control: what the client's buffer level lets the server send.

The client says up to which media time it holds data (``received``) and how much of that it
has not played yet (``buffered``); ``received - buffered`` is its playhead. An item stamped
``t`` may go out once ``t < playhead + window``. Reports only move the playhead forward (a
late, reordered report cannot pull it back). A client that leaves the server waiting with no
report for ``stall_timeout`` seconds has stalled: :class:`Stalled` is raised, and the server
closes it instead of holding its utterance open for ever.
"""
from __future__ import annotations

import asyncio
import time

WINDOW = 2.0  # s of media the server sends ahead of the client's playhead
STALL_TIMEOUT = 30.0  # s a client may leave the server waiting with no buffer report


class Stalled(Exception):
    """No buffer report for ``stall_timeout`` s while the window was full."""


class Flow:
    def __init__(self, window: float, stall_timeout: float, clock=time.monotonic) -> None:
        if not window > 0 or not stall_timeout > 0:
            raise ValueError(f"window ({window!r}) and stall_timeout ({stall_timeout!r}) must be > 0 s")
        self.window, self.stall_timeout, self.clock = float(window), float(stall_timeout), clock
        self.playhead = 0.0
        self.last_report = clock()
        self.reports = 0
        self.waits = 0  # how often sending had to wait for the client
        self._moved = asyncio.Event()

    def restart(self) -> None:
        """A new utterance: media time starts again at 0."""
        self.playhead, self.last_report = 0.0, self.clock()
        self._moved.set()

    def report(self, received: float, buffered: float) -> None:
        self.playhead = max(self.playhead, received - buffered)
        self.last_report = self.clock()
        self.reports += 1
        self._moved.set()

    def allows(self, t: float) -> bool:
        return t < self.playhead + self.window

    async def wait_for(self, t: float) -> None:
        """Return once an item at media time ``t`` may be sent; raise :class:`Stalled` if the client is silent."""
        if self.allows(t):
            return
        self.waits += 1
        while not self.allows(t):
            left = self.last_report + self.stall_timeout - self.clock()
            if left <= 0:
                raise Stalled(f"no buffer report for {self.stall_timeout:g} s with the window full "
                              f"(playhead {self.playhead:.2f} s, next item at {t:.2f} s)")
            self._moved.clear()
            try:
                await asyncio.wait_for(self._moved.wait(), timeout=left)
            except asyncio.TimeoutError:
                continue
