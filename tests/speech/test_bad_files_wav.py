"""Damaged and oversized WAVs given to --speech are one AlignError at their byte, refused from the
header (issue 26: 5 of 150 mutated WAVs ended in a RuntimeError from wave.py; a 1-hour WAV peaked at
1.85 GB before it was refused)."""
from __future__ import annotations

import struct

import numpy as np
import pytest

from mpeg4fa.speech.align.errors import AlignError
from mpeg4fa.speech.align.recording import read_recording
from mpeg4fa.wavread import MAX_SECONDS, WavError, read_wav, wav_info


def wav_bytes(samples: np.ndarray, rate: int = 16000, channels: int = 1, tag: int = 1, bits: int = 16,
              data_size: int | None = None, extra: bytes = b"") -> bytes:
    data = samples.tobytes()
    block = channels * bits // 8
    fmt = struct.pack("<HHIIHH", tag, channels, rate, rate * block, block, bits)
    size = len(data) if data_size is None else data_size
    body = b"WAVE" + b"fmt " + struct.pack("<I", len(fmt)) + fmt + extra + b"data" + struct.pack("<I", size) + data
    return b"RIFF" + struct.pack("<I", len(body)) + body


TONE = (np.sin(np.arange(1600) * 0.1) * 8000).astype("<i2")


def test_a_good_wav_reads_as_before(tmp_path):
    path = tmp_path / "ok.wav"
    path.write_bytes(wav_bytes(TONE))
    samples, rate = read_wav(path)
    assert rate == 16000 and np.array_equal(samples, TONE)
    stereo = np.repeat(TONE[:, None], 2, axis=1)
    path.write_bytes(wav_bytes(stereo, channels=2))
    assert np.array_equal(read_wav(path)[0], TONE)
    path.write_bytes(wav_bytes((TONE / 32768).astype("<f4"), tag=3, bits=32))
    assert np.abs(read_wav(path)[0].astype(int) - TONE).max() <= 1


@pytest.mark.parametrize("data, where, words", [
    (wav_bytes(TONE)[:30], "byte 12", "'fmt ' chunk is 16 bytes, past the end"),
    (wav_bytes(TONE, data_size=10_000_000), "byte 36", "declares 10,000,000 bytes"),
    (wav_bytes(TONE)[:44], "byte 36", "declares 3,200 bytes but the file ends 0 bytes after"),
    (wav_bytes(np.zeros(0, "<i2"), data_size=0), "", "holds no samples"),
    (wav_bytes(TONE, extra=b"LIST" + struct.pack("<I", 1 << 30)), "byte 36", "'LIST' declares"),
    (wav_bytes(TONE, extra=b"\x00\x01\x02\x03" + bytes(4)), "byte 36", "not a four-letter code"),
    (wav_bytes(TONE, tag=2), "byte 20", "compressed or unknown"),
    (wav_bytes(TONE, rate=0), "byte 24", "sample rate 0 Hz"),
    (wav_bytes(TONE, channels=0), "byte 22", "0 channels"),
    (b"\xff\xd8\xff\xe0" + bytes(60), "byte 0", "(a JPEG image)"),
    (b"RIFF\x10\x00\x00\x00AVI LIST", "byte 8", "form b'AVI '"),
])
def test_damage_is_one_error_at_its_byte(tmp_path, data, where, words):
    path = tmp_path / "bad.wav"
    path.write_bytes(data)
    with pytest.raises(AlignError) as info:
        read_recording(path)
    text = str(info.value)
    assert text.startswith(f"{path}{': ' + where if where else ''}: ") and words in text


def test_mutated_wavs_never_escape(tmp_path):
    rng = np.random.default_rng(26)
    good = wav_bytes(TONE)
    path = tmp_path / "m.wav"
    for _ in range(150):
        data = bytearray(good)
        for _ in range(int(rng.integers(1, 6))):
            data[int(rng.integers(0, 60))] = int(rng.integers(0, 256))
        path.write_bytes(bytes(data[: int(rng.integers(8, len(data) + 1))]))
        try:
            read_recording(path)
        except AlignError:
            pass


def test_too_long_is_refused_from_the_header(tmp_path):
    path = tmp_path / "hour.wav"
    seconds = MAX_SECONDS + 60
    header = wav_bytes(np.zeros(0, "<i2"), rate=48000, data_size=int(seconds * 48000 * 2))
    with open(path, "wb") as fh:  # a sparse file: the samples are never written, nor read
        fh.write(header)
        fh.truncate(len(header) + int(seconds * 48000 * 2))
    assert wav_info(path).seconds == pytest.approx(seconds)
    with pytest.raises(WavError, match=r"lasts 31.0 min, more than the 30 min read"):
        read_wav(path)
    with pytest.raises(AlignError, match="30 min"):
        read_recording(path)
