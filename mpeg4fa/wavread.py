"""The package's one WAV reader: RIFF chunks walked by hand, every fault at its byte, bounded before reading.

The stdlib :mod:`wave` ends damaged files in ``RuntimeError``/``EOFError`` tracebacks, reads only integer
PCM, and sizes nothing before it reads: a one-hour WAV was decoded whole (1.85 GB) before anything said
it was too long. :func:`read_wav` instead

1. reads the chunk headers only (``RIFF``/``WAVE``, ``fmt ``, ``data``; others skipped), each checked
   against the file's real size: a chunk that runs past the end, a ``fmt `` that is short or says
   something impossible, a missing ``data`` chunk are one :class:`WavError` at ``path: byte N``;
2. refuses, from the header alone, a recording longer than ``max_seconds`` (default :data:`MAX_SECONDS`,
   30 min) or of an unsupported kind (8/16/24/32-bit integer PCM and 32/64-bit IEEE float, plain or
   ``WAVE_FORMAT_EXTENSIBLE``; 1 to :data:`MAX_CHANNELS` channels; :data:`MIN_RATE` to :data:`MAX_RATE` Hz);
3. reads the samples block by block into mono int16 (channels averaged), so memory is the result
   (2 bytes a sample) plus one block, and time is linear in the file.

A ``data`` size of 0 or 0xFFFFFFFF (what a streaming writer leaves before it knows the length) means
"to the end of the file". A file that is not RIFF is named by its signature (:mod:`mpeg4fa.filetype`).
The module imports nothing above :mod:`mpeg4fa.errors`, so every layer can use it.
"""
from __future__ import annotations

import os
import struct
from dataclasses import dataclass

import numpy as np

from mpeg4fa.errors import MpegFaError, unreadable
from mpeg4fa.filetype import HEAD_BYTES, foreign_kind, head_hex

__all__ = ["WavError", "WavInfo", "MAX_SECONDS", "MAX_SPEECH_SECONDS", "MAX_CHANNELS", "MIN_RATE", "MAX_RATE", "wav_info", "read_wav"]

MAX_SPEECH_SECONDS = 30 * 60.0
"""Longest speech the in-memory encoder takes (30 min): a ``--speech`` recording and ``--visemes`` events
(:data:`mpeg4fa.speech.viseme_events.MAX_SECONDS`) are timed whole and, by the library's
``encode_utterance``, coded whole, in time and memory that grow with the duration (30 min of visemes: about
6 s and 400 MB). Kept here, at the bottom of the package, so that the WAV reader and the speech layer read
one number."""
MAX_SECONDS = MAX_SPEECH_SECONDS
"""Longest recording read by default, refused from the header before any sample is read."""
MAX_CHANNELS = 64
MIN_RATE = 1000
MAX_RATE = 768_000
_BLOCK_FRAMES = 1 << 18
"""Sample frames converted at a time: bounds the float scratch memory to a few MB whatever the length."""
_PCM, _FLOAT, _EXTENSIBLE = 1, 3, 0xFFFE


class WavError(MpegFaError, ValueError):
    """A WAV file that cannot be read: ``where`` is ``path`` or ``path: byte N``."""

    def __init__(self, message: str, where: str | None = None, hint: str = "") -> None:
        super().__init__(message, where, hint)


@dataclass(frozen=True)
class WavInfo:
    """What the header says: enough to size the work before reading a sample."""

    path: str
    format: str          # "pcm" or "float"
    channels: int
    rate: int
    bits: int
    data_offset: int     # byte where the samples start
    frames: int          # sample frames in the data chunk (as far as the file holds them)

    @property
    def seconds(self) -> float:
        return self.frames / self.rate


def _fail(path: str, offset: int | None, message: str, hint: str = "") -> WavError:
    return WavError(message, path if offset is None else f"{path}: byte {offset}", hint)


def wav_info(path: str | os.PathLike) -> WavInfo:
    """The header of a WAV file, checked (see the module docstring); no sample is read."""
    name = os.fsdecode(path)
    try:
        with open(path, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            return _walk(fh, name, size)
    except OSError as exc:
        problem, hint = unreadable(exc)
        raise WavError(problem, name, hint or "give the WAV file of the speech") from None


def _walk(fh, name: str, size: int) -> WavInfo:
    head = fh.read(12)
    if head[:4] != b"RIFF" or head[8:12] != b"WAVE":
        head += fh.read(HEAD_BYTES)
        kind = foreign_kind(head)
        if not head:
            raise _fail(name, None, "the file is empty", "give a WAV recording")
        if head[:4] == b"RIFF":
            raise _fail(name, 8, f"not a WAV file: a RIFF file of form {head[8:12]!r}, not 'WAVE'",
                        "give a RIFF/WAVE recording")
        if kind is not None and kind != "a WAV audio file":
            raise _fail(name, 0, f"not a WAV file: starts with {head_hex(head)} ({kind})",
                        "a file's content, not its name, says what it is")
        raise _fail(name, 0, f"not a WAV file: starts with {head_hex(head)}, not RIFF....WAVE",
                    "give a RIFF/WAVE recording")
    fmt: tuple[int, int, int, int, int] | None = None
    pos = 12
    while True:
        header = fh.read(8)
        if len(header) < 8:
            if fmt is None:
                raise _fail(name, pos, "no 'fmt ' chunk before the end of the file", "the file is truncated or not a WAV")
            raise _fail(name, pos, "no 'data' chunk before the end of the file", "the file is truncated")
        chunk, length = header[:4], struct.unpack("<I", header[4:])[0]
        body = pos + 8
        if chunk == b"fmt ":
            if length < 16 or body + length > size:
                raise _fail(name, pos, f"the 'fmt ' chunk is {length} bytes" +
                            (", past the end of the file" if length >= 16 else ", shorter than 16"),
                            "the file is damaged")
            fmt = _format(fh.read(min(length, 40)), name, body)
        elif chunk == b"data":
            if fmt is None:
                raise _fail(name, pos, "the 'data' chunk comes before any 'fmt ' chunk", "the file is damaged")
            tag, channels, rate, block, bits = fmt
            if length in (0, 0xFFFFFFFF):  # a streaming writer's placeholder: to the end of the file
                length = size - body
            elif body + length > size:
                raise _fail(name, pos, f"the 'data' chunk declares {length:,} bytes but the file ends "
                            f"{size - body:,} bytes after it starts", "the file is truncated")
            return WavInfo(name, "float" if tag == _FLOAT else "pcm", channels, rate, bits, body, length // block)
        elif not (chunk.isascii() and all(32 <= c < 127 for c in chunk)):
            raise _fail(name, pos, f"chunk id {chunk!r} is not a four-letter code", "the file is damaged")
        if body + length > size:
            raise _fail(name, pos, f"chunk {chunk.decode('ascii')!r} declares {length:,} bytes, past the end of "
                        "the file", "the file is damaged")
        pos = body + length + (length & 1)
        fh.seek(pos)


def _format(data: bytes, name: str, at: int) -> tuple[int, int, int, int, int]:
    tag, channels, rate, _, block, bits = struct.unpack("<HHIIHH", data[:16])
    if tag == _EXTENSIBLE:
        if len(data) < 40:
            raise _fail(name, at, "WAVE_FORMAT_EXTENSIBLE without its 24-byte extension", "the file is damaged")
        tag = struct.unpack("<H", data[24:26])[0]
    if tag not in (_PCM, _FLOAT):
        raise _fail(name, at, f"format {tag:#06x} is a compressed or unknown encoding",
                    "give PCM (8-32 bit integer) or IEEE float samples")
    allowed = (8, 16, 24, 32) if tag == _PCM else (32, 64)
    if bits not in allowed:
        raise _fail(name, at + 14, f"{bits}-bit {'integer' if tag == _PCM else 'float'} samples are not read",
                    f"give {', '.join(map(str, allowed))}-bit samples")
    if not 1 <= channels <= MAX_CHANNELS:
        raise _fail(name, at + 2, f"{channels} channels (1 to {MAX_CHANNELS} are read)", "the file is damaged")
    if not MIN_RATE <= rate <= MAX_RATE:
        raise _fail(name, at + 4, f"sample rate {rate:,} Hz ({MIN_RATE:,} to {MAX_RATE:,} are read)",
                    "the file is damaged")
    if block != channels * bits // 8:
        raise _fail(name, at + 12, f"block align {block} is not {channels} channels x {bits // 8} bytes",
                    "the file is damaged")
    return tag, channels, rate, block, bits


def read_wav(path: str | os.PathLike, *, max_seconds: float = MAX_SECONDS) -> tuple[np.ndarray, int]:
    """``(mono int16 samples, rate)`` of a WAV file; :class:`WavError` at the byte at fault.

    A recording longer than ``max_seconds`` is refused from its header, before reading samples.
    """
    info = wav_info(path)
    if info.seconds > max_seconds:
        raise WavError(f"the recording lasts {info.seconds / 60:,.1f} min, more than the {max_seconds / 60:g} min "
                       "read", info.path, "cut the recording into parts and align each with its transcript")
    if info.frames == 0:
        raise WavError("the recording holds no samples", info.path, "give a WAV file with the speech")
    out = np.empty(info.frames, dtype=np.int16)
    width = info.bits // 8
    try:
        with open(path, "rb") as fh:
            fh.seek(info.data_offset)
            for start in range(0, info.frames, _BLOCK_FRAMES):
                n = min(_BLOCK_FRAMES, info.frames - start)
                raw = fh.read(n * width * info.channels)
                if len(raw) < n * width * info.channels:  # the file shrank since its header was read
                    raise WavError("the file ends inside its samples", f"{info.path}: byte "
                                   f"{info.data_offset + start * width * info.channels + len(raw)}",
                                   "the file is truncated")
                out[start:start + n] = _mono_int16(raw, info)
    except OSError as exc:
        problem, hint = unreadable(exc)
        raise WavError(problem, info.path, hint) from None
    return out, info.rate


def _mono_int16(raw: bytes, info: WavInfo) -> np.ndarray:
    if info.format == "float":
        # full scale is +-1: NaN is silence, beyond (inf, 1e308) is clipped here, before the channels are
        # summed (1e308 + 1e308 overflows, inf - inf is NaN: numpy warnings, then a NaN cast to int16). A
        # signalling NaN (float32 0x7f800001) raises "invalid" in the cast to float64: it is read as any NaN
        with np.errstate(invalid="ignore"):
            x = np.frombuffer(raw, "<f4" if info.bits == 32 else "<f8").astype(np.float64)
            x = np.clip(np.nan_to_num(x, nan=0.0, posinf=1.0, neginf=-1.0), -1.0, 1.0)
    elif info.bits == 8:
        x = (np.frombuffer(raw, np.uint8).astype(np.float64) - 128.0) / 128.0
    elif info.bits == 16:
        x = np.frombuffer(raw, "<i2").astype(np.float64) / 32768.0
    elif info.bits == 24:
        b = np.frombuffer(raw, np.uint8).reshape(-1, 3).astype(np.int32)
        v = b[:, 0] | (b[:, 1] << 8) | (b[:, 2] << 16)
        x = np.where(v >= 1 << 23, v - (1 << 24), v).astype(np.float64) / float(1 << 23)
    else:
        x = np.frombuffer(raw, "<i4").astype(np.float64) / float(1 << 31)
    x = x.reshape(-1, info.channels).mean(axis=1)
    return np.clip(np.rint(x * 32768.0), -32768, 32767).astype(np.int16)


