"""decode() holds each integer array as narrow as its values allow (issue 26 item 7: a 300 KB stream of
tiny frames held ~400 bytes a frame), widens the whole array the moment a value does not fit, and gives
the same stream on both backends; consumers widen before arithmetic."""
from __future__ import annotations

import mmap
import numpy as np
import pytest

from mpeg4fa.fba import EncodeOptions, FapStream, decode, encode
from mpeg4fa.fba import stacking
from mpeg4fa.fba.compiled import available
from mpeg4fa.fba.stacking import StreamBuilder
from mpeg4fa.fba.stream import STORAGE, fits, narrowed
from mpeg4fa.formats import read_fap, write_fap

from .conftest import FRAME_FIELDS, assert_streams_equal

BACKENDS = ["python", pytest.param("compiled", marks=pytest.mark.skipif(not available(), reason="no numba here"))]
HEAD = 46  # FAP 47, a head rotation: quantiser step 512, so values pass int16 at a few dozen levels


def holds_only_its_rows(a: np.ndarray) -> bool:
    """``a`` is the whole of the memory under it (not a view into a larger block that stays alive)."""
    base = a
    while isinstance(base, np.ndarray) and base.base is not None:
        base = base.base
    return (len(base) if isinstance(base, mmap.mmap) else base.nbytes) == a.nbytes


@pytest.fixture(scope="module")
def tiny() -> bytes:
    """3,000 frames of about 6 bits: one FAP, a value of -1, 0 or 1 (the issue's stream, shorter)."""
    s = FapStream.empty(3000)
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = np.arange(3000) % 3 - 1
    s.timestamps[:] = np.arange(3000) / 25.0
    return encode(s, EncodeOptions(fps=25, intra_period=0))


@pytest.fixture(scope="module")
def wide_source() -> FapStream:
    """A head rotation in small steps (int16 holds it), then past 32767 from frame 40 on, with FAP 1 blend
    climbing past int8 in P frames and a skip past int8."""
    n = 60
    s = FapStream.empty(n)
    s.fap_mask[:, [0, 2, HEAD]] = True
    s.fap_values[:, 2] = 4 * (np.arange(n) % 5 - 2)  # FAP 3's step is 4
    s.fap_values[:, HEAD] = np.where(np.arange(n) < 40, 512 * (np.arange(n) % 7), 512 * (60 + 10 * np.arange(n)))
    s.viseme[:, 0], s.viseme[:, 2] = 3, np.minimum(np.arange(n) * 60, 2000)
    s.skip[30] = 200
    s.timestamps[:] = np.concatenate([[0], np.cumsum(s.skip[:-1].astype(np.int64) + 1)]) / 25.0
    return s


@pytest.fixture
def small_blocks(monkeypatch):
    """Storage blocks of 16 frames and add() blocks of 7: a few dozen frames cross many boundaries."""
    monkeypatch.setattr(stacking, "STORE_BLOCK", 16)
    monkeypatch.setattr(stacking, "BLOCK", 7)


@pytest.mark.parametrize("backend", BACKENDS)
def test_tiny_frames_hold_at_most_230_bytes_a_frame(tiny, backend):
    s = decode(tiny, backend=backend)
    assert len(s) == 3000
    per_frame = s.nbytes / len(s)
    assert per_frame <= 230, per_frame  # 401 before: fap_values int32, viseme/expression/skip/bits int32
    assert s.fap_values.dtype == np.int16 and s.viseme.dtype == np.int8 and s.skip.dtype == np.int8
    assert encode(s, backend=backend) == tiny  # narrow arrays re-encode to the same bytes


@pytest.mark.parametrize("blocks", [False, True], ids=["blocks", "small-blocks"])
def test_values_past_int16_widen_the_whole_array_and_both_backends_agree(wide_source, blocks, request):
    if blocks:
        request.getfixturevalue("small_blocks")
    data = encode(wide_source, EncodeOptions(fps=25, fap_quant=1, intra_period=0))
    streams = [decode(data, backend="python")] + ([decode(data, backend="compiled")] if available() else [])
    for s in streams:
        assert s.fap_values.dtype == np.int32 and s.viseme.dtype == np.int16 and s.skip.dtype == np.int16
        assert s.fap_values[:, HEAD].max() > 32767
        np.testing.assert_array_equal(s.fap_values, wide_source.fap_values)  # every step a multiple of 512
        np.testing.assert_array_equal(s.viseme, wide_source.viseme)
        np.testing.assert_array_equal(s.skip, wide_source.skip)
        assert_streams_equal(s, streams[0], FRAME_FIELDS)
        assert encode(s) == data


def test_nbytes_counts_a_shared_row_once(tiny):
    s = decode(tiny)
    assert s.bap_values.strides[0] == 0  # no body: one zero row for every frame
    own = sum(getattr(s, name).nbytes for name in ("fap_mask", "fap_values", "viseme", "expression", "timestamps",
                                                     "object_mask", "skip", "start_code", "bits"))
    assert s.nbytes == own + 296 * (1 + 4)
    assert FapStream.empty(10).nbytes == 10 * (68 + 272 + 16 + 24 + 296 * 5 + 8 + 1 + 4 + 4 + 4)


def test_headroom_is_half_the_range():
    """A value stays narrow while the sum or difference of two values cannot wrap."""
    assert fits(np.int16, -16384, 16383) and not fits(np.int16, 0, 16384) and not fits(np.int16, -16385, 0)
    assert fits(np.uint16, 0, 0x1BB) and not fits(np.uint16, -1, 0)
    assert narrowed(np.array([0, 16383]), "fap_values").dtype == np.int16
    assert narrowed(np.array([0, 16384]), "fap_values").dtype == np.int32
    assert narrowed(np.array([0, 63]), "viseme").dtype == np.int8
    assert narrowed(np.array([-64, 64]), "viseme").dtype == np.int16
    assert narrowed(np.array([1 << 40]), "bits").dtype == np.int32  # the widest rung holds what int32 did


def test_builder_widens_each_field_by_what_its_values_need(small_blocks):
    builder = StreamBuilder()
    rows = []
    for k in range(40):  # the big values arrive late: every earlier block is widened
        row = dict(fap_mask=np.ones(68, bool), fap_values=np.full(68, k - 20, np.int32),
                   viseme=np.array([1, 2, k, 0]), expression=np.array([1, -k, 2, 3, 0, 1]), timestamp=k / 25,
                   skip=k * 10, start_code=0x1BB if k == 5 else 0, bits=40000 if k == 33 else k)
        if k == 37:
            row["fap_values"] = np.full(68, -70000, np.int32)
        rows.append(row)
        builder.add(**row)
        if k == 30:  # 28 rows stored so far, in 2 blocks of 16
            assert builder.dtypes["fap_values"] == np.int16 and builder.dtypes["skip"] == np.int16
    s = builder.build()
    want = {"fap_values": np.int32, "viseme": np.int8, "expression": np.int8, "skip": np.int16,
            "start_code": np.uint16, "bits": np.int32}
    assert {name: getattr(s, name).dtype for name in want} == {name: np.dtype(d) for name, d in want.items()}
    for name in ("fap_values", "viseme", "expression"):
        np.testing.assert_array_equal(getattr(s, name), [r[name] for r in rows], err_msg=name)
    for name in ("skip", "start_code", "bits"):
        np.testing.assert_array_equal(getattr(s, name), [r[name] for r in rows], err_msg=name)
    assert s.fap_values.flags.writeable and holds_only_its_rows(s.fap_values)


def test_widen_makes_a_decoded_stream_safe_to_write(tiny):
    s = decode(tiny).copy()
    assert s.fap_values.dtype == np.int16
    assert s.widen() is s
    assert {name: getattr(s, name).dtype for name in STORAGE} == {name: np.dtype(d[-1]) for name, d in STORAGE.items()}
    s.fap_values[0, 2] = 100_000
    assert int(s.fap_values[0, 2]) == 100_000


def test_a_fap_file_gap_past_int8_keeps_its_skip(tmp_path):
    """The .fap reader writes skips after building: a gap of 300 frames must not wrap in a narrow array."""
    s = FapStream.empty(3)
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = [1, 2, 3]
    s.skip[:] = [299, 40_000, 0]
    s.source_fps = 25.0
    s.timestamps[:] = np.array([0, 300, 40_301]) / 25.0
    write_fap(s, tmp_path / "gap.fap")
    back = read_fap(tmp_path / "gap.fap")
    assert back.skip.tolist() == [299, 40_000, 0] and back.skip.dtype == np.int32
    assert back.duration == pytest.approx(40_302 / 25.0)


@pytest.mark.skipif(not available(), reason="no numba here")
def test_compiled_encoder_takes_narrow_streams_without_new_kernel_versions(tiny, wide_source):
    """The kernels are typed for int32 arrays: narrow ones are cast at their boundary, not compiled again."""
    from mpeg4fa.fba.compiled import kernels

    narrow = decode(tiny)
    encode(narrow, EncodeOptions(fps=25, intra_period=50), backend="compiled")
    encode(narrow, backend="compiled")
    for kernel in (kernels.encode_planes, kernels.first_overflow, kernels.closed_loop_extremes):
        for signature in kernel.signatures:
            assert not any(str(t).startswith(("array(int16", "array(int8", "array(uint16"))
                           for t in signature), (kernel.__name__, signature)
