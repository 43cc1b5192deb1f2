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


WAV_MAX_BYTES = 0xFFFFFFFF - 36
"""Most bytes of samples a WAV file holds (its sizes are 32-bit): 27 hours of 16-bit mono at 22050 Hz."""


class PcmWriter:
    """16-bit PCM WAV written as the samples come, into an open binary file (a partial output that
    :func:`mpeg4fa.atomic.atomic_output` puts in place): long speech is never held whole. The header's
    sizes are filled in by :meth:`close`; ``name`` is the file the user sees, for errors."""

    def __init__(self, handle, rate: int, channels: int = 1, name: str = "<wav>") -> None:
        self.name = name
        self.bytes = 0
        self._out = wave.open(handle, "wb")
        self._out.setnchannels(channels)
        self._out.setsampwidth(2)
        self._out.setframerate(int(rate))

    def write(self, pcm: np.ndarray) -> None:
        """Append ``pcm`` (int16, ``(n,)`` or ``(n, channels)``)."""
        data = np.ascontiguousarray(np.asarray(pcm).astype("<i2", copy=False)).tobytes()
        if self.bytes + len(data) > WAV_MAX_BYTES:
            from mpeg4fa.errors import MpegFaError
            raise MpegFaError(f"the speech is longer than a WAV file holds ({WAV_MAX_BYTES:,} bytes of samples)",
                              where=self.name, hint="split the text and encode the parts one after another")
        self._out.writeframesraw(data)
        self.bytes += len(data)

    def close(self) -> None:
        """Write the header's final sizes (the file itself stays open: its owner closes it)."""
        self._out.close()

    def abandon(self) -> None:
        """Give up the file (an error stopped the writing): nothing more is written to it, not even by the
        ``wave`` writer's own clean-up once the file is closed."""
        self._out._file = None
