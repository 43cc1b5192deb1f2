"""A recording to align: any PCM WAV (8/16/24/32-bit integer or 32/64-bit float, any rate and channel
count) read into mono int16 at its own rate, plus the resampling and speech-energy checks the aligners need.

The stdlib :mod:`wave` reads integer PCM; a WAV it refuses (IEEE float, WAVE_FORMAT_EXTENSIBLE) is
decoded with PyAV (a dependency already). Channels are averaged. Resampling is
:func:`scipy.signal.resample_poly` (polyphase, anti-aliased).
"""
from __future__ import annotations

import os
import wave
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mpeg4fa.speech.align.errors import AlignError

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


def _read_wave(path: Path) -> tuple[np.ndarray, int]:
    with open(path, "rb") as handle, wave.open(handle, "rb") as w:
        channels, width, rate, n = w.getnchannels(), w.getsampwidth(), w.getframerate(), w.getnframes()
        raw = w.readframes(n)
    if width == 1:
        x = (np.frombuffer(raw, np.uint8).astype(np.float64) - 128.0) / 128.0
    elif width == 2:
        x = np.frombuffer(raw, "<i2").astype(np.float64) / 32768.0
    elif width == 3:
        b = np.frombuffer(raw, np.uint8).reshape(-1, 3).astype(np.int32)
        v = b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16)
        x = np.where(v >= 1 << 23, v - (1 << 24), v).astype(np.float64) / float(1 << 23)
    elif width == 4:
        x = np.frombuffer(raw, "<i4").astype(np.float64) / float(1 << 31)
    else:
        raise AlignError(f"{8 * width}-bit samples are not supported", where=str(path),
                         hint="give 8, 16, 24 or 32-bit PCM")
    usable = len(x) // channels * channels
    return x[:usable].reshape(-1, channels).mean(axis=1), rate


def _read_av(path: Path) -> tuple[np.ndarray, int]:
    import av

    chunks, rate = [], 0
    with av.open(str(path)) as container:
        if not container.streams.audio:
            raise AlignError("the file has no audio stream", where=str(path), hint="give a WAV recording")
        stream = container.streams.audio[0]
        rate = int(stream.codec_context.sample_rate or stream.rate)
        resampler = av.AudioResampler(format="flt", layout="mono", rate=rate)
        for frame in container.decode(stream):
            chunks += [f.to_ndarray().reshape(-1) for f in resampler.resample(frame)]
        chunks += [f.to_ndarray().reshape(-1) for f in resampler.resample(None)]
    return (np.concatenate(chunks).astype(np.float64) if chunks else np.zeros(0)), rate


def read_recording(path: str | os.PathLike) -> Recording:
    """Read a WAV file as mono int16 at its own rate; :class:`AlignError` naming the file if it cannot."""
    path = Path(path)
    if not path.exists():
        raise AlignError("no such recording", where=str(path), hint="give the WAV file of the speech with --speech")
    if not path.is_file():
        raise AlignError("not a file", where=str(path), hint="give the WAV file of the speech with --speech")
    try:
        x, rate = _read_wave(path)
    except AlignError:
        raise
    except (wave.Error, EOFError, ValueError) as exc:
        try:
            x, rate = _read_av(path)
        except AlignError:
            raise
        except Exception:  # noqa: BLE001 - any decoder failure is "cannot read"
            raise AlignError(f"cannot read the recording ({exc})", where=str(path),
                             hint="give a PCM WAV file (8-32 bit integer or float samples)") from None
    except OSError as exc:
        raise AlignError(f"cannot read the recording ({exc.strerror or exc})", where=str(path),
                         hint="check the file can be read") from None
    if rate <= 0 or len(x) == 0:
        raise AlignError("the recording holds no samples", where=str(path), hint="give a WAV file with the speech")
    return Recording(_to_int16(np.clip(x, -1.0, 1.0)), int(rate), str(path))


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
