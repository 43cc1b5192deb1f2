"""decode() and from_frames() hold a stream in memory proportional to its arrays (fba.stacking)."""
from __future__ import annotations

import gc
import tracemalloc

import numpy as np
import pytest

from mpeg4fa.fba import EncodeOptions, FapStream, decode, encode, iter_decode
from mpeg4fa.fba import stacking
from mpeg4fa.fba.stacking import StreamBuilder, stack_frames
from mpeg4fa.formats import read_fap, write_fap

from .conftest import FRAME_FIELDS, assert_streams_equal, make_stream

FACE_MASK = np.zeros(68, dtype=bool)
FACE_MASK[[0, 1, 2, 3, 4, 18, 47]] = True


def _stacked_the_plain_way(frames) -> FapStream:
    """What from_frames did before: one row per frame into FapStream.empty."""
    frames = list(frames)
    s = FapStream.empty(len(frames))
    for k, f in enumerate(frames):
        for name in ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values"):
            getattr(s, name)[k] = getattr(f, name)
        s.timestamps[k], s.object_mask[k], s.skip[k] = f.timestamp, f.object_mask, f.skip
        s.start_code[k], s.bits[k] = f.start_code, f.bits
        if f.params is not None:
            s.intra[k] = f.params
    return s


@pytest.fixture
def small_blocks(monkeypatch):
    """Blocks of 7 frames, so that a few dozen frames cross several block boundaries."""
    monkeypatch.setattr(stacking, "BLOCK", 7)


def test_face_stream_shares_one_read_only_body_row(small_blocks):
    data = encode(make_stream(1, 30, fap_mask=FACE_MASK), EncodeOptions(fap_quant=2, intra_period=8))
    s = decode(data)
    assert s.bap_mask.shape == (30, 296) and s.bap_values.shape == (30, 296)
    assert not s.bap_mask.any() and not s.bap_values.any()
    assert s.bap_mask.strides[0] == 0 and not s.bap_mask.flags.writeable  # no memory per frame
    for other in (s.copy(), s.take([0, 3, 5])):
        assert other.bap_values.strides[0] == 0 and not other.bap_values.flags.writeable
    assert s.take([0, 3, 5]).bap_mask.shape == (3, 296)
    assert encode(s) == data                                       # still re-encodes to the same bytes
    assert_streams_equal(s, _stacked_the_plain_way(iter_decode(data)))


def test_body_frames_across_blocks(small_blocks):
    bap_mask = np.arange(296) < 12
    s = make_stream(4, 25, fap_mask=FACE_MASK, bap_mask=bap_mask)
    s.object_mask[:9] = 1                                          # the body joins in the second block
    s.bap_mask[:9] = False
    s.bap_values[:9] = 0
    data = encode(s, EncodeOptions(bap_quant=1))
    d = decode(data)
    assert d.bap_mask.flags.writeable and d.bap_mask.strides[0] != 0
    assert_streams_equal(d, _stacked_the_plain_way(iter_decode(data)))
    assert d.bap_mask[9:].any() and not d.bap_mask[:9].any() and encode(d) == data


def test_from_frames_and_the_builder_agree_with_plain_stacking(small_blocks):
    data = encode(make_stream(9, 40, fap_mask=FACE_MASK, bap_mask=np.arange(296) < 5), EncodeOptions())
    frames = list(iter_decode(data))
    plain = _stacked_the_plain_way(frames)
    assert_streams_equal(FapStream.from_frames(frames), plain)
    assert_streams_equal(stack_frames(frames[:1]), _stacked_the_plain_way(frames[:1]))
    assert sorted(FapStream.from_frames(frames).intra) == sorted(plain.intra)
    empty = StreamBuilder().build()
    assert len(empty) == 0 and empty.bap_mask.shape == (0, 296) and empty.fap_values.shape == (0, 68)


def test_partial_stream_of_a_truncated_decode_uses_the_builder(small_blocks):
    data = encode(make_stream(2, 30, fap_mask=FACE_MASK), EncodeOptions(fap_quant=1, intra_period=10))
    full = decode(data)
    try:
        decode(data[: len(data) * 2 // 3])
    except Exception as exc:  # an FbaError with the frames before the fault
        partial = exc.partial
    assert 0 < len(partial) < len(full)
    assert_streams_equal(partial, full, FRAME_FIELDS, len(partial))


def test_read_fap_builds_without_body_rows(tmp_path):
    s = make_stream(3, 20, fap_mask=FACE_MASK)
    s.skip[4] = 7
    path = tmp_path / "a.fap"
    write_fap(s, path)
    back = read_fap(path)
    assert back.bap_mask.strides[0] == 0 and back.skip[4] == 7 and back.skip[-1] == 0
    assert np.array_equal(back.fap_values, s.fap_values) and np.array_equal(back.viseme, s.viseme)
    assert np.allclose(back.timestamps, np.concatenate([[0], np.cumsum(back.skip[:-1] + 1)]) / 25.0)


def test_decode_peak_is_under_a_kilobyte_a_frame():
    """tracemalloc peak of decode() over a few thousand frames of a face stream (the old decoder took ~4.7 KB)."""
    n = 6000
    s = make_stream(5, n, fap_mask=np.isin(np.arange(68), [2, 3]), hold=0.9)
    data = encode(s, EncodeOptions(fap_quant=31))
    gc.collect()
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        stream = decode(data)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    assert len(stream) == n
    assert peak / n < 1024, f"decode() peak {peak / n:.0f} bytes a frame"
