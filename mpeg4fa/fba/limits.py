"""What a stream may ask of the codec: frame rates the bitstream can carry, and how long it may span.

A few bytes can ask for absurd work: a ``.fap`` file with frame numbers 0 and
2147483647 asks the encoder for 2**31 held frames (megabytes of skip codes,
minutes of work). These bounds turn such requests into one clear error:

* frame rate: an intra header sends 8 bits of whole frames and 4 bits of sixteenths
  (plus a 1000/1001 flag), so ``1/16 <= fps <= 255 15/16`` (:meth:`FrameRate.from_fps`);
* span: a stream covers at most :data:`MAX_SPAN_SECONDS` (24 h) of frames at its rate,
  counting skipped frames (:func:`frame_limit`, :func:`check_span`);
* frames held: :func:`~mpeg4fa.fba.decode` holds at most :data:`MAX_DECODE_FRAMES` (2**21) frames.
"""
from __future__ import annotations

import math

import numpy as np

from .errors import FbaError
from .stream import FapStream, FrameRate

MAX_SPAN_SECONDS = 24 * 3600
"""Longest stretch of time a stream may cover, skipped frames included: 24 hours."""
MAX_DECODE_FRAMES = 1 << 21
"""Most frames :func:`~mpeg4fa.fba.decode` holds in memory: 2,097,152 (23.3 h at 25 fps; about 480 MB at the
228 bytes a frame of a face stream of small values, 763 MB at 364 when FAP values need int32, face only); a
6-bit frame makes this a 1.5 MB stream. :func:`~mpeg4fa.fba.iter_decode` has no such ceiling (constant memory)."""


def fps_problem(fps: object) -> str | None:
    """Why ``fps`` cannot be sent in an intra header, or None when it can (one rule: :meth:`FrameRate.from_fps`)."""
    try:
        FrameRate.from_fps(fps)  # type: ignore[arg-type]
    except FbaError as exc:
        return exc.message
    return None


def frame_limit(fps: float) -> int:
    """How many frames (coded and skipped) a stream at ``fps`` may span: :data:`MAX_SPAN_SECONDS` of them.

    Counted at the rate the intra header will carry (``fps`` rounded to sixteenths), so that a ``.fap``
    file, its planned stream and the stream written agree on the bound.
    """
    return max(1, int(math.floor(MAX_SPAN_SECONDS * FrameRate.from_fps(fps).fps)))


def span_hint(fps: float) -> str:
    return (f"a stream may span at most {MAX_SPAN_SECONDS // 3600} h, {frame_limit(fps):,} frames at {fps:g} fps; "
            "split the material into several streams")


def check_span(stream: FapStream, fps: float) -> None:
    """Raise an :class:`FbaError` at the first frame with a negative skip or past the span limit."""
    skip = np.asarray(stream.skip, dtype=np.int64)
    if len(skip) and skip.min() < 0:
        k = int(np.argmax(skip < 0))
        raise FbaError(f"skip count {int(skip[k])} is negative", frame=k,
                       hint="skip counts the frames left out after a frame")
    slots = np.cumsum(skip + 1)  # grid slots used up to and including each frame's skipped ones
    limit = frame_limit(fps)
    if len(slots) and slots[-1] > limit:
        k = int(np.argmax(slots > limit))
        raise FbaError(f"the stream spans {int(slots[-1]):,} frames ({int(slots[-1]) / fps / 3600:,.1f} h at "
                       f"{fps:g} fps), more than a stream may", frame=k, hint=span_hint(fps))
