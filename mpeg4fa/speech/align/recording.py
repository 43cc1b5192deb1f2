"""A recording to align: any PCM WAV (8/16/24/32-bit integer or 32/64-bit float, any rate and channel
count) read into mono int16 at its own rate, plus the resampling and speech-energy checks the aligners need.

WAV is read by the package's one WAV reader (:mod:`mpeg4fa.wavread`: damage located at its byte, at
most 30 minutes, refused from the header); MP3, AAC, FLAC, Ogg and MP4 audio are decoded with PyAV (a
dependency already) within the same ceiling. Channels are averaged. Resampling is
:func:`scipy.signal.resample_poly` (polyphase, anti-aliased).
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mpeg4fa.filetype import HEAD_BYTES, foreign_kind
from mpeg4fa.speech.align.errors import AlignError
from mpeg4fa.wavread import MAX_SECONDS, WavError, read_wav

HOP = 0.01
"""Analysis frame step (s): pocketsphinx's, and the DTW's."""


@dataclass(frozen=True)
class Recording:
    """Mono int16 samples at the file's own rate, and where they came from."""

    samples: np.ndarray
    rate: int
    name: str = "<recording>"

    @property
    def duration(self) -> float:
        return len(self.samples) / self.rate

    def floats(self) -> np.ndarray:
        return self.samples.astype(np.float64) / 32768.0


def _to_int16(x: np.ndarray) -> np.ndarray:
    return np.clip(np.rint(x * 32768.0), -32768, 32767).astype(np.int16)


_OTHER_AUDIO = ("an MP3 audio file", "an AAC (ADTS) audio file", "a FLAC audio file", "an Ogg audio file",
                "an MP4/QuickTime file")
"""Kinds of file read through PyAV when they are not WAV (:mod:`mpeg4fa.filetype` names them)."""


def _read_av(path: Path, max_seconds: float) -> tuple[np.ndarray, int]:
    """Compressed audio decoded with PyAV, refused past ``max_seconds`` (from the container when it says,
    else as soon as the decoded samples pass it)."""
    import av

    chunks, rate, total = [], 0, 0
    with av.open(str(path)) as container:
        if not container.streams.audio:
            raise AlignError("the file has no audio stream", where=str(path), hint="give a WAV recording")
        if container.duration is not None and container.duration / 1e6 > max_seconds:
            raise _too_long(container.duration / 1e6, max_seconds, str(path))
        stream = container.streams.audio[0]
        rate = int(stream.codec_context.sample_rate or stream.rate)
        resampler = av.AudioResampler(format="s16", layout="mono", rate=rate)
        for frame in container.decode(stream):
            for f in resampler.resample(frame):
                chunks.append(f.to_ndarray().reshape(-1).astype(np.int16))
                total += len(chunks[-1])
            if total > max_seconds * rate:
                raise _too_long(total / rate, max_seconds, str(path))
        chunks += [f.to_ndarray().reshape(-1).astype(np.int16) for f in resampler.resample(None)]
    return (np.concatenate(chunks) if chunks else np.zeros(0, np.int16)), rate


def _too_long(seconds: float, max_seconds: float, where: str) -> AlignError:
    return AlignError(f"the recording lasts {seconds / 60:,.1f} min or more, more than the {max_seconds / 60:g} min "
                      "read", where=where, hint="cut the recording into parts and align each with its transcript")


def read_recording(path: str | os.PathLike, max_seconds: float = MAX_SECONDS) -> Recording:
    """Read a WAV file (or MP3, AAC, FLAC, Ogg, MP4 audio through PyAV) as mono int16 at its own rate.

    WAV goes through :func:`mpeg4fa.wavread.read_wav` (every fault at its byte, the length checked from the
    header, memory 2 bytes a sample); anything else is an :class:`AlignError` naming the file.
    """
    path = Path(path)
    if not path.exists():
        raise AlignError("no such recording", where=str(path), hint="give the WAV file of the speech with --speech")
    if not path.is_file():
        raise AlignError("not a file", where=str(path), hint="give the WAV file of the speech with --speech")
    try:
        samples, rate = read_wav(path, max_seconds=max_seconds)
    except WavError as exc:
        try:
            with open(path, "rb") as fh:
                kind = foreign_kind(fh.read(HEAD_BYTES))
        except OSError:
            kind = None
        if kind not in _OTHER_AUDIO:
            raise AlignError(f"cannot read the recording: {exc.message}", where=exc.where, hint=exc.hint) from None
        try:
            samples, rate = _read_av(path, max_seconds)
        except AlignError:
            raise
        except Exception as av_exc:  # noqa: BLE001 - any decoder failure is "cannot read"
            raise AlignError(f"cannot read the recording as {kind} ({av_exc})", where=str(path),
                             hint="give a PCM WAV file (8-32 bit integer or float samples)") from None
    if rate <= 0 or len(samples) == 0:
        raise AlignError("the recording holds no samples", where=str(path), hint="give a WAV file with the speech")
    return Recording(samples, int(rate), str(path))


def resample(x: np.ndarray, rate: int, target: int) -> np.ndarray:
    """``x`` (float, mono) from ``rate`` to ``target`` Hz."""
    if rate == target:
        return np.asarray(x, dtype=np.float64)
    from scipy.signal import resample_poly

    g = int(np.gcd(int(rate), int(target)))
    return resample_poly(np.asarray(x, dtype=np.float64), target // g, rate // g)


SILENCE_DBFS = -50.0
"""A recording whose loudest 10 ms frame is quieter than this holds no speech."""
SPEECH_RANGE_DB = 35.0
"""Frames quieter than the loud end of the recording (its 95th percentile frame) by more than this are not speech."""
NOISE_MARGIN_DB = 12.0
"""Speech frames stand this far above the noise floor (the 10th percentile frame), or 15 dB below the loud
end where the recording is nearly all speech. On the LibriVox recordings of pocketsphinx's tests this puts
the speech's start within 15-85 ms of the speech/silence labels those tests expect (.lab), where the loud
end alone took the room noise before it for speech (0 s)."""


def frame_levels(x: np.ndarray, rate: int, hop: float = HOP) -> np.ndarray:
    """Level (dBFS) of each ``hop``-second frame of ``x`` (float in [-1, 1])."""
    n = max(1, int(round(hop * rate)))
    frames = len(x) // n
    if frames == 0:
        return np.full(1, -120.0)
    power = (x[:frames * n].reshape(frames, n) ** 2).mean(axis=1)
    return 10 * np.log10(np.maximum(power, 1e-12))


def speech_frames(levels: np.ndarray) -> np.ndarray:
    """Which frames carry speech energy: above the noise floor by :data:`NOISE_MARGIN_DB`, within
    :data:`SPEECH_RANGE_DB` of the loud end, above -60 dBFS."""
    loud, floor = float(np.percentile(levels, 95)), float(np.percentile(levels, 10))
    return levels >= max(min(floor + NOISE_MARGIN_DB, loud - 15.0), loud - SPEECH_RANGE_DB, -60.0)


def check_speech(rec: Recording) -> np.ndarray:
    """The recording's speech frames (see :func:`speech_frames`); AlignError if it is silent."""
    levels = frame_levels(rec.floats(), rec.rate)
    if levels.max() < SILENCE_DBFS or speech_frames(levels).sum() * HOP < 0.05:
        raise AlignError(f"the recording is silent (loudest 10 ms at {levels.max():.0f} dBFS)", where=rec.name,
                         hint="give a recording of the transcript being spoken")
    return speech_frames(levels)
