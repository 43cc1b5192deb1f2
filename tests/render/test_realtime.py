"""Live pacing (fake clock, so slow rendering is simulated exactly) and the Tk preview window."""
from __future__ import annotations

import itertools
import os
import shutil
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.realtime import THREAD_NAME, LiveStats, live
from mpeg4fa.render.window import display_available, ppm_bytes, show

PERIOD = 0.04  # 25 fps


class FakeClock:
    """A clock that only moves when slept on or advanced by a simulated render."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            self.now += seconds

    def renderer(self, cost):
        """A render callable taking ``cost(item)`` (or a constant) seconds of fake time."""
        def render(item):
            self.now += cost(item) if callable(cost) else cost
            return ("image", item)
        return render


def stamps(n: int, period: float = PERIOD, start: float = 5.0) -> list[float]:
    return [start + i * period for i in range(n)]


def play(clock: FakeClock, source, cost, **kwargs):
    return live(source, clock.renderer(cost), timestamp=lambda t: t, clock=clock, sleep=clock.sleep, **kwargs)


def test_cheap_render_shows_every_frame_on_time():
    clock, stats = FakeClock(), LiveStats()
    frames = list(play(clock, stamps(50), 0.002, stats=stats))
    assert [f.index for f in frames] == list(range(50))
    for f in frames:
        assert f.due == pytest.approx(f.timestamp - 5.0)
        assert abs(f.shown_at - f.due) < 1e-3
        assert f.lateness < 1e-3
        assert f.image == ("image", f.item)
    assert stats.rendered == 50 and stats.dropped == 0 and stats.stalls == 0
    assert stats.period == pytest.approx(PERIOD)


def test_slow_render_drops_frames_without_growing_drift():
    clock, stats = FakeClock(), LiveStats()
    frames = list(play(clock, stamps(500), 1.5 * PERIOD, stats=stats))
    assert stats.dropped > 100 and stats.rendered + stats.dropped == 500
    assert 0.5 < stats.rendered / 500 < 0.8  # about one frame per render time
    assert stats.max_lateness < 2 * PERIOD
    late = [f.lateness for f in frames]
    assert max(late[-50:]) <= max(late[:50]) + 1e-9  # no accumulated drift
    assert frames[-1].shown_at - frames[-1].due < 2 * PERIOD


def test_burst_drops_stale_frames_then_back_on_time():
    clock, stats = FakeClock(), LiveStats()
    frames = list(play(clock, stamps(60), lambda t: 10 * PERIOD if t == stamps(60)[10] else 0.1 * PERIOD, stats=stats))
    shown = [f.index for f in frames]
    assert 10 in shown
    skipped = set(range(60)) - set(shown)
    assert skipped and min(skipped) == 11 and max(skipped) <= 20 and 7 <= len(skipped) <= 10
    after = [f for f in frames if f.index > 10]
    assert after[0].lateness < PERIOD
    assert all(f.lateness < 1e-9 for f in after[1:])


def test_slow_first_render_is_start_up_latency_not_lateness():
    clock, stats = FakeClock(), LiveStats()
    frames = list(play(clock, stamps(20), lambda t: 8 * PERIOD if t == 5.0 else 0.001, stats=stats))
    assert stats.dropped == 0 and all(f.lateness < 1e-9 for f in frames)


def test_last_item_is_shown_even_when_late():
    clock = FakeClock()
    frames = list(play(clock, stamps(5), lambda t: 10 * PERIOD if t == stamps(5)[2] else 0.001))
    assert [f.index for f in frames] == [0, 1, 2, 4]  # 3 dropped for the newer 4; 4 has nothing newer
    assert frames[-1].lateness > PERIOD


def test_source_error_reraised_after_earlier_frames():
    class Boom(Exception):
        pass

    def source():
        yield from stamps(5)
        raise Boom("link lost")

    clock, got = FakeClock(), []
    with pytest.raises(Boom, match="link lost") as info:
        for frame in play(clock, source(), 0.001):
            got.append(frame.index)
    assert got == [0, 1, 2, 3, 4]
    assert any("reader thread" in note for note in info.value.__notes__)


def test_stalled_source_raises_within_stall_timeout():
    release = threading.Event()

    def source():
        yield from stamps(3)
        release.wait(5.0)
        yield 99.0

    clock, stats, got = FakeClock(), LiveStats(), []
    try:
        with pytest.raises(RenderError, match="source stalled: no frame for 0.2 s") as info:
            for frame in play(clock, source(), 0.001, stall_timeout=0.2, stats=stats):
                got.append(frame.index)
                began = time.monotonic()
        waited = time.monotonic() - began
    finally:
        release.set()
    assert got == [0, 1, 2]
    assert 0.15 < waited < 1.0
    assert info.value.where == "live source" and info.value.hint
    assert stats.stalls == 1


def _new_reader_threads(before):
    return [t for t in threading.enumerate() if t.name == THREAD_NAME and t not in before]


def test_close_stops_reader_thread():
    before = set(threading.enumerate())
    clock = FakeClock()
    frames = play(clock, (5.0 + i * PERIOD for i in itertools.count()), 0.001)
    for _ in range(5):
        next(frames)
    (reader,) = _new_reader_threads(before)
    assert reader.is_alive() and reader.daemon
    began = time.monotonic()
    frames.close()
    reader.join(1.0)
    assert not reader.is_alive()
    assert time.monotonic() - began < 1.0


def test_queue_bounds_read_ahead():
    produced = []

    def source():
        for t in stamps(1000):
            produced.append(t)
            yield t

    clock = FakeClock()
    frames = play(clock, source(), 0.001, queue_size=4)
    next(frames)
    time.sleep(0.05)
    assert len(produced) <= 4 + 3  # queue + one looked ahead + one waiting to be put
    frames.close()


def test_backwards_timestamp_raises_with_index():
    clock = FakeClock()
    with pytest.raises(RenderError, match="item 3") as info:
        list(play(clock, [0.0, 0.04, 0.08, 0.06, 0.12], 0.001))
    assert "backwards" in str(info.value)


def test_bad_arguments():
    with pytest.raises(ValueError):
        live([], lambda x: x, timestamp=float, stall_timeout=0)
    with pytest.raises(ValueError):
        live([], lambda x: x, timestamp=float, queue_size=0)
    assert list(live([], lambda x: x, timestamp=float)) == []


def test_real_clock_paces_to_wall_time():
    began = time.monotonic()
    frames = list(live([i / 100 for i in range(10)], lambda t: t, timestamp=lambda t: t))
    took = time.monotonic() - began
    assert len(frames) == 10
    assert 0.07 <= took <= 0.5
    assert all(f.shown_at >= f.due - 1e-3 for f in frames)


# --- window ---------------------------------------------------------------

def test_ppm_bytes():
    image = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)
    data = ppm_bytes(image)
    assert data.startswith(b"P6 3 2 255\n") and data.endswith(image.tobytes())
    assert ppm_bytes(np.zeros((2, 3, 4), np.uint8)) == b"P6 3 2 255\n" + bytes(18)
    with pytest.raises(RenderError):
        ppm_bytes(np.zeros((2, 3), np.uint8))
    with pytest.raises(RenderError):
        ppm_bytes(np.zeros((2, 3, 3), np.float32))


@pytest.mark.skipif(sys.platform in ("win32", "darwin"), reason="DISPLAY only decides on X11/Wayland systems")
def test_no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert display_available() is False
    consumed = []

    def frames():
        consumed.append(1)
        yield np.zeros((4, 4, 3), np.uint8)

    with pytest.raises(RenderError, match="no display") as info:
        show(frames())
    assert "DISPLAY" in info.value.hint
    assert not consumed


@pytest.fixture
def xvfb_display(monkeypatch):
    binary = shutil.which("Xvfb")
    if binary is None:
        pytest.skip("Xvfb not installed")
    read_fd, write_fd = os.pipe()
    server = subprocess.Popen(
        [binary, "-displayfd", str(write_fd), "-screen", "0", "320x240x24", "-nolisten", "tcp"],
        pass_fds=(write_fd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )
    os.close(write_fd)
    try:
        with os.fdopen(read_fd) as pipe:
            number = pipe.readline().strip()  # Xvfb writes the free display it took once it is ready
        if not number:
            pytest.skip("Xvfb did not start")
        monkeypatch.setenv("DISPLAY", f":{number}")
        monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
        yield f":{number}"
    finally:
        server.terminate()
        server.wait(5)


def test_show_on_xvfb(xvfb_display):
    import tkinter

    assert display_available()
    seen = []

    def frames():
        for i in range(5):
            root = tkinter._default_root
            seen.append(root is not None and bool(root.winfo_exists()) and root.title())
            yield np.full((16, 24, 3), 40 * i, np.uint8)

    began = time.monotonic()
    show(frames(), title="live test", fps_hint=50, linger=0.05)
    assert time.monotonic() - began < 3.0
    assert seen == ["live test"] * 5  # the window was up while frames were pulled
    assert tkinter._default_root is None  # and destroyed afterwards
