"""A float WAV holding signalling NaNs reads as silence there, without a numpy warning (fuzz campaign full3,
target wav: 'RuntimeWarning wavread.py:195: invalid value encountered in cast' in every chunk of 5,000 cases:
a bit flip in a float32 sample's exponent makes 0x7f800001-like patterns, whose cast to float64 raises)."""
from __future__ import annotations

import struct
import warnings

import numpy as np
import pytest

from mpeg4fa.wavread import read_wav


def _wav(path, words: list[int], bits: int, channels: int = 1):
    data = np.array(words, "<u4" if bits == 32 else "<u8").tobytes()
    block = channels * bits // 8
    fmt = struct.pack("<HHIIHH", 3, channels, 8000, 8000 * block, block, bits)
    path.write_bytes(b"RIFF" + struct.pack("<I", 36 + len(data)) + b"WAVEfmt " + struct.pack("<I", 16) + fmt
                     + b"data" + struct.pack("<I", len(data)) + data)
    return path


@pytest.mark.parametrize("words, bits, channels, expected", [
    ([0x7F800001, 0x3F000000] * 4, 32, 1, [0, 16384]),           # signalling NaN, then 0.5
    ([0xFFA00000, 0x3F000000] * 4, 32, 2, [8192, 8192]),         # negative signalling NaN beside 0.5
    ([0x7FF0000000000001, 0x3FE0000000000000] * 4, 64, 1, [0, 16384]),
])
def test_signalling_nan_is_silence_without_a_warning(tmp_path, words, bits, channels, expected):
    path = _wav(tmp_path / "snan.wav", words, bits, channels)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out, rate = read_wav(path)
    assert rate == 8000 and out[:2].tolist() == expected
