"""16-bit PCM WAV files, written whole or not at all: the speech's audio track, in one place.

The stdlib ``wave`` module does the format; this adds what both the speech layer and the
renderer need: the file appears only when complete (:func:`mpeg4fa.atomic.atomic_output`),
and a file that cannot be opened fails cleanly (``wave.open(name)`` leaves a half-made writer
whose ``__del__`` fails after the error, so the file object is ours).
"""
from __future__ import annotations

import os
import wave

import numpy as np

from mpeg4fa.atomic import atomic_output


def write_pcm16(path: "str | os.PathLike[str]", pcm: np.ndarray, rate: int) -> None:
    """Write ``pcm`` (int16, ``(n,)`` mono or ``(n, channels)``) at ``rate`` Hz; OSError if it cannot."""
    frames = np.asarray(pcm).astype("<i2", copy=False)
    channels = 1 if frames.ndim == 1 else frames.shape[1]
    with atomic_output(path) as partial, open(partial, "wb") as handle, wave.open(handle, "wb") as out:
        out.setnchannels(channels)
        out.setsampwidth(2)
        out.setframerate(int(rate))
        out.writeframes(np.ascontiguousarray(frames).tobytes())
