"""Reading a video for tracking: its frames one at a time as RGB arrays, its frame rate, and its sound.

Through PyAV (FFmpeg's libraries, as :mod:`mpeg4fa.render.video` writes MP4s), so any file
FFmpeg reads works and memory stays that of one frame. A file that is not a video, has no
video stream, or breaks part-way is one :class:`~.errors.TrackingError` naming the file (and
the frame); nothing here writes.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from mpeg4fa.errors import unreadable
from mpeg4fa.tracking.errors import TrackingError

MAX_SIDE = 8192
"""Largest frame side read (an 8K frame is 200 MB of RGB): refused from the header."""
MAX_SECONDS = 3600.0
"""Longest video tracked (1 h, as `play --audio`): the tracked points and values are kept in memory."""


@dataclass(frozen=True)
class VideoInfo:
    """What a video's header says: size, frame rate, frames (estimated when the container does not say),
    and whether it has sound."""

    path: str
    width: int
    height: int
    fps: float
    frames: int
    has_audio: bool


def _open(path: Path):
    import av

    where = str(path)
    if not path.is_file():
        if path.exists():
            raise TrackingError("is a directory, not a video file" if path.is_dir() else "not a regular file", where)
        raise TrackingError("no such video file", where, "check the path and the current directory")
    try:
        container = av.open(where)
    except OSError as exc:
        if isinstance(exc, av.FFmpegError):
            raise TrackingError("not a video FFmpeg can read", where,
                                "give an MP4, MOV, MKV, WebM or AVI file with a video track") from None
        raise TrackingError(*unreadable(exc)[:1], where=where, hint=unreadable(exc)[1]) from None
    except (av.FFmpegError, ValueError) as exc:
        raise TrackingError(f"not a video FFmpeg can read ({exc})", where) from None
    if not container.streams.video:
        container.close()
        raise TrackingError("the file has no video track", where, "give a video file, not an image or audio file")
    return container


def probe_video(path: str | os.PathLike) -> VideoInfo:
    """The video's header facts; TrackingError for a file that is not a readable video within the limits."""
    path = Path(path)
    container = _open(path)
    try:
        return _info(container, path)
    finally:
        container.close()


def _info(container, path: Path) -> VideoInfo:
    where = str(path)
    stream = container.streams.video[0]
    width, height = int(stream.codec_context.width or 0), int(stream.codec_context.height or 0)
    if not (0 < width <= MAX_SIDE and 0 < height <= MAX_SIDE):
        raise TrackingError(f"frames of {width} x {height} pixels (at most {MAX_SIDE} a side)", where)
    rate = stream.average_rate or stream.guessed_rate or stream.base_rate
    fps = float(rate) if rate else 0.0
    seconds = float(container.duration) / 1e6 if container.duration else 0.0
    if stream.duration and stream.time_base:
        seconds = max(seconds, float(stream.duration * stream.time_base))
    if seconds > MAX_SECONDS:
        raise TrackingError(f"the video lasts {seconds:,.0f} s, more than {MAX_SECONDS:,.0f} s", where,
                            "cut it into parts and track each")
    frames = int(stream.frames) if stream.frames else int(round(seconds * fps))
    return VideoInfo(where, width, height, fps, frames, bool(container.streams.audio))


def read_frames(path: str | os.PathLike, fps: float | None = None) -> Iterator[np.ndarray]:
    """Every frame of the video as an (H, W, 3) uint8 RGB array, in order; a TrackingError naming the file
    and frame if decoding breaks. ``fps`` (the rate the frames are taken at) only bounds how many are read."""
    for _, rgb in timed_frames(path, fps):
        yield rgb


def timed_frames(path: str | os.PathLike, fps: float | None = None) -> Iterator[tuple[float, np.ndarray]]:
    """:func:`read_frames` with each frame's presentation time, seconds from the first frame's. A webcam's video
    often has a variable frame rate: its frames come when they come, not every 1/fps (so counting frames puts a
    face's motion early or late against its sound). A frame without a time, or one not after the last, is taken
    one frame period (at the header's rate) after the frame before."""
    import av

    path = Path(path)
    where = str(path)
    container = _open(path)
    try:
        info = _info(container, path)
        rate = fps or info.fps or 30.0
        limit = int(MAX_SECONDS * rate) + 1
        stream = container.streams.video[0]
        stream.thread_type = "AUTO"
        period = 1.0 / (info.fps or rate)
        tick = float(stream.time_base) if stream.time_base else 0.0
        k, first, last = 0, None, -period
        try:
            for frame in container.decode(stream):
                if k >= limit:
                    raise TrackingError(f"more than {limit:,} frames ({MAX_SECONDS:,.0f} s)", where,
                                        "cut it into parts and track each")
                t = frame.time
                if t is not None and first is None:
                    first = t - k * period
                t = t - first if t is not None and first is not None else None
                if t is not None and info.fps and tick:  # a stamp rounded to its time base (MKV and WebM: whole
                    grid = round(t * info.fps) / info.fps  # ms, 33 ms apart at 30 fps) is on the header's grid
                    t = grid if abs(t - grid) <= tick / 2 + 1e-9 else t
                last = t if t is not None and t > last + 1e-6 else last + period
                if last > MAX_SECONDS:  # a time stamp hours on: every output frame up to it would be tracked
                    raise TrackingError(f"frame {k} is stamped {last:,.0f} s after the first, more than "
                                        f"{MAX_SECONDS:,.0f} s", where, "the file's time stamps are damaged")
                yield last, frame.to_ndarray(format="rgb24")
                k += 1
        except (av.FFmpegError, ValueError, OSError) as exc:
            raise TrackingError(f"frame {k}: cannot decode the video ({exc})", where,
                                "the file is damaged or cut short") from None
        if k == 0:
            raise TrackingError("the video holds no frames", where)
    finally:
        container.close()


def frame_showing(path: str | os.PathLike, seconds: float, fps: float | None = None) -> tuple[int, np.ndarray]:
    """The frame of the video on screen ``seconds`` after its first (the last one stamped at or before that time,
    :func:`timed_frames` at ``fps``, as the tracker took them) as (its number, RGB); decoded from the start: exact
    for any codec and frame rate."""
    shown = None
    for k, (t, rgb) in enumerate(timed_frames(path, fps)):
        if t > seconds + 1e-6 and shown is not None:
            break
        shown = (k, rgb)
    if shown is None:
        raise TrackingError("the video holds no frames", str(path))
    return shown
