"""The frame rate an intra header can carry, from ``spec/frame_rate.csv`` (its three fields and their widths).

One rule for every reader and the encoder: a rate is sendable when it lies in
``[FPS_MIN, FPS_MAX]`` (before the 1000/1001 flag), i.e. 1/16 to 255 15/16 frames per second.
"""
from __future__ import annotations

from mpeg4fa.spec._load import check, read_table

_ROWS = {r["field"]: r for r in read_table("frame_rate.csv", "field,bits,step,meaning")}
check(set(_ROWS) == {"frame_rate", "seconds", "frequency_offset"}, "frame_rate.csv must list the three fields")

FRAME_RATE_BITS = int(_ROWS["frame_rate"]["bits"])
"""Width of ``frame_rate`` (whole frames per second)."""
SECONDS_BITS = int(_ROWS["seconds"]["bits"])
"""Width of ``seconds`` (fractions of a frame per second)."""
FREQUENCY_OFFSET_BITS = int(_ROWS["frequency_offset"]["bits"])
"""Width of the 1000/1001 flag."""
FPS_STEPS = round(1 / float(_ROWS["seconds"]["step"]))
"""Fractions a frame per second is split into by ``seconds`` (16)."""
check(FPS_STEPS == 1 << SECONDS_BITS, "seconds must count 1/2**bits of a frame")

FPS_MIN = 1 / FPS_STEPS
"""Slowest rate a header carries: 1/16 frame per second."""
FPS_MAX = (1 << FRAME_RATE_BITS) - 1 + (FPS_STEPS - 1) / FPS_STEPS
"""Fastest rate a header carries: 255 15/16 frames per second."""
FPS_RANGE_TEXT = f"1/{FPS_STEPS} to {(1 << FRAME_RATE_BITS) - 1} {FPS_STEPS - 1}/{FPS_STEPS}"
"""The range in words, as messages give it: ``1/16 to 255 15/16``."""
