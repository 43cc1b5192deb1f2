"""Speech audio for playback: read any file FFmpeg reads, fit it to a video's length.

Samples are float32 in [-1, 1], shaped ``(n, channels)``; the rate is kept as read
(the AAC encoder resamples if it must).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mpeg4fa.render.errors import RenderError


@dataclass(frozen=True)
class Audio:
    samples: np.ndarray  # (n, channels) float32
    rate: int

    @property
    def duration(self) -> float:
        return len(self.samples) / self.rate

    @property
    def channels(self) -> int:
        return int(self.samples.shape[1])

    def mono(self) -> np.ndarray:
        """One channel (the mean), for analysis."""
        return self.samples.mean(axis=1)


MAX_AUDIO_SECONDS = 3600.0
"""Longest audio read for playback (1 h: 1.4 GB of float32 at 48 kHz stereo); refused from the header when it
says so, else when decoding passes it, so a small file cannot ask for unbounded memory."""


def _too_long(path: Path, seconds: float, limit: float) -> RenderError:
    return RenderError(f"the audio lasts more than {limit:,.0f} s ({seconds:,.0f} s read or announced)",
                       where=str(path), hint="cut it to the stream's length first (audio beyond a stream is not "
                                             "played)")


def read_audio(path: str | os.PathLike, *, max_seconds: float = MAX_AUDIO_SECONDS) -> Audio:
    """Decode an audio file (WAV or anything FFmpeg reads) into float32 samples, at most ``max_seconds``."""
    import av

    path = Path(path)
    if not path.is_file():
        raise RenderError("no such audio file" if not path.exists() else "not a file", where=str(path),
                          hint="give a WAV (or other audio) file with --audio")
    chunks: list[np.ndarray] = []
    try:
        with av.open(str(path)) as container:
            if not container.streams.audio:
                raise RenderError("the file has no audio stream", where=str(path))
            stream = container.streams.audio[0]
            rate = int(stream.codec_context.sample_rate or stream.rate)
            if rate <= 0:
                raise RenderError("the audio stream has no sample rate", where=str(path), hint="the file is damaged")
            announced = container.duration / av.time_base if container.duration else 0.0
            if announced > max_seconds:
                raise _too_long(path, announced, max_seconds)
            limit, total = int(max_seconds * rate), 0
            resampler = av.AudioResampler(format="flt", layout=stream.layout.name if stream.layout else None,
                                          rate=rate)
            try:
                for frame in container.decode(stream):
                    for out in resampler.resample(frame):
                        chunks.append(out.to_ndarray().reshape(-1, len(out.layout.channels)))
                        total += len(chunks[-1])
                    if total > limit:
                        raise _too_long(path, total / rate, max_seconds)
                for out in resampler.resample(None):
                    chunks.append(out.to_ndarray().reshape(-1, len(out.layout.channels)))
            except (av.FFmpegError, ValueError) as exc:  # opened as audio, then broken: damage, not the wrong type
                raise RenderError(f"the sound is damaged or cut short after {total / rate:.2f} s ({exc})",
                                  where=str(path), hint="export or copy the file again") from None
    except RenderError:
        raise
    except (av.FFmpegError, ValueError, OSError) as exc:
        raise RenderError(f"cannot read audio: {exc}", where=str(path),
                          hint="a WAV, FLAC, MP3, Ogg or M4A file is expected") from None
    if not chunks:
        raise RenderError("the audio stream holds no samples", where=str(path))
    samples = np.concatenate(chunks).astype(np.float32, copy=False)
    return Audio(samples=samples, rate=rate)


def fit_audio(audio: Audio, duration: float) -> Audio:
    """The audio cut, or padded with silence, to exactly ``duration`` seconds (the caller says why)."""
    target = max(int(round(duration * audio.rate)), 0)
    n = len(audio.samples)
    if n >= target:
        return Audio(audio.samples[:target], audio.rate)
    pad = np.zeros((target - n, audio.channels), dtype=np.float32)
    return Audio(np.concatenate([audio.samples, pad]), audio.rate)
