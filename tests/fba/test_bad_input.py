"""Damaged, hostile and unsupported input: only FbaError (or a clean decode), never a hang or another exception."""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mpeg4fa import spec
from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, UnsupportedFeature, decode, encode, iter_decode
from mpeg4fa.fba.stream import (END_CODE, OBJECT_START_CODE, OBJECT_START_CODE_OLD, PLANE_START_CODE,
                                PLANE_START_CODE_OLD)

from .conftest import (FBA_VECTORS, FRAME_FIELDS, GROUP_SIZES, GROUP_SLICES, SKIP_REASON, VALUE_FIELDS,
                       assert_same_on_grid, assert_streams_equal, hyp_settings, make_stream, mask_from_types,
                       time_limit)

HYP = hyp_settings(40)
PER_DECODE_LIMIT = 5  # seconds: a decode of a few hundred bytes takes milliseconds

SMALL_MASK = np.zeros(68, dtype=bool)
SMALL_MASK[[0, 1, 2, 3, 4, 18, 47, 50]] = True  # FAP 1, FAP 2, jaw and lips, an eyelid, head pitch, a lip
SMALL_OPTIONS = EncodeOptions(fap_quant=2, intra_period=4, start_codes=True)


def _small_stream() -> FapStream:
    return make_stream(0, 10, fap_mask=SMALL_MASK, hold=0.2)


SMALL = encode(_small_stream(), SMALL_OPTIONS)
"""~250 bytes: FAP 1, FAP 2 and low-level FAPs, three intra frames, plane start codes."""
SMALL_BODY = encode(make_stream(3, 4, fap_mask=SMALL_MASK, bap_mask=np.arange(296) < 12), EncodeOptions(bap_quant=5))
"""Face and body together."""

VOTE = FBA_VECTORS / "en" / "vote-unlock.FBA"


def _vote_or_skip() -> bytes:
    if not VOTE.is_file():
        pytest.skip(f"{SKIP_REASON} (en/vote-unlock.FBA missing)")
    return VOTE.read_bytes()


def streams_under_test():
    """(id, bytes) of the small streams; the real vote-unlock.FBA when it is there."""
    out = [pytest.param(SMALL, id="generated-face"), pytest.param(SMALL_BODY, id="generated-face+body")]
    if VOTE.is_file():
        out.append(pytest.param(VOTE.read_bytes(), id="en/vote-unlock.FBA"))
    else:
        out.append(pytest.param(None, id="en/vote-unlock.FBA", marks=pytest.mark.skip(reason=SKIP_REASON)))
    return out


def decode_or_error(data: bytes) -> FapStream | FbaError:
    """decode() under a time limit: the stream, or the FbaError it raised (any other exception propagates)."""
    start = time.perf_counter()
    with time_limit(PER_DECODE_LIMIT):
        try:
            result = decode(data)
        except FbaError as exc:
            result = exc
    assert time.perf_counter() - start < PER_DECODE_LIMIT
    return result


def check_error(exc: FbaError, data: bytes, full: FapStream | None = None) -> None:
    """An FbaError that says where (an int bit offset inside the data) and keeps what was decoded."""
    assert isinstance(exc.bit_offset, int), exc
    assert 0 <= exc.bit_offset <= 8 * len(data), exc
    assert isinstance(exc.partial, FapStream)
    n = len(exc.partial)
    assert exc.frame is None or isinstance(exc.frame, int)
    assert str(exc)  # the message renders
    if full is not None:  # the frames decoded before the fault are those of the intact stream
        assert n <= len(full)
        assert_streams_equal(exc.partial, full, FRAME_FIELDS, n)
        assert sorted(exc.partial.intra) == [k for k in sorted(full.intra) if k < n]


def test_small_stream_is_what_the_tests_want():
    assert 200 <= len(SMALL) <= 600
    s = decode(SMALL)
    assert len(s) == 10 and sorted(s.intra) == [0, 4, 8]
    assert s.fap_mask[:, :2].all() and s.fap_mask[:, 2:].any()
    assert (s.start_code[[0, 4, 8]] == PLANE_START_CODE).all()
    assert encode(s) == SMALL
    assert set(decode(SMALL_BODY).object_mask.tolist()) == {3}


# ---- truncation ------------------------------------------------------------------------------
@pytest.mark.parametrize("data", streams_under_test())
def test_every_truncation_raises_fba_error_with_a_prefix(data):
    full = decode(data)
    for length in range(len(data)):
        cut = data[:length]
        result = decode_or_error(cut)
        assert isinstance(result, FbaError), f"a stream cut to {length} of {len(data)} bytes decoded"
        check_error(result, cut, full)
        if length >= 4:
            assert result.frame == len(result.partial), (length, result)


def test_truncated_file_streams_frames_then_raises(tmp_path):
    path = tmp_path / "cut.fba"
    path.write_bytes(SMALL[: len(SMALL) * 2 // 3])
    frames = []
    with pytest.raises(FbaError) as info:
        with open(path, "rb") as fh:
            for frame in iter_decode(fh):
                frames.append(frame)
    assert 0 < len(frames) < 10
    assert info.value.frame == len(frames)
    with pytest.raises(FbaError) as info2:
        decode(path)
    assert len(info2.value.partial) == len(frames)


# ---- corruption ----------------------------------------------------------------------------
def _check_corrupt(data: bytes) -> None:
    result = decode_or_error(data)
    if isinstance(result, FbaError):
        check_error(result, data)
        return
    # it decoded: what it decoded to must be a stream the encoder can write back (or refuse cleanly)
    assert len(result) > 0
    try:
        again = encode(result)
    except FbaError:
        return
    assert_same_on_grid(decode(again), result)


@pytest.mark.parametrize("data", streams_under_test())
def test_every_single_bit_flip(data):
    outcomes = {"error": 0, "decoded": 0}
    for bit in range(8 * len(data)):  # each decode runs under decode_or_error's time limit
        bad = bytearray(data)
        bad[bit // 8] ^= 0x80 >> (bit % 8)
        result = decode_or_error(bytes(bad))
        outcomes["error" if isinstance(result, FbaError) else "decoded"] += 1
        if isinstance(result, FbaError):
            check_error(result, bytes(bad))
    assert outcomes["error"] > 0  # flips in start codes and markers at least are caught


@HYP
@given(data=st.sampled_from([SMALL, SMALL_BODY]), flips=st.lists(st.integers(0, 10**6), min_size=2, max_size=24))
def test_random_multi_bit_corruption(data, flips):
    bad = bytearray(data)
    for f in flips:
        bit = f % (8 * len(data))
        bad[bit // 8] ^= 0x80 >> (bit % 8)
    _check_corrupt(bytes(bad))


@HYP
@given(data=st.sampled_from([SMALL, SMALL_BODY]), at=st.integers(0, 10**6), junk=st.binary(min_size=1, max_size=40))
def test_overwritten_bytes(data, at, junk):
    at %= len(data)
    bad = data[:at] + junk + data[at + len(junk):]
    _check_corrupt(bad)


@HYP
@given(tail=st.binary(max_size=300), end=st.booleans())
def test_random_bytes_after_object_start_code(tail, end):
    data = OBJECT_START_CODE.to_bytes(4, "big") + tail + (b"\x7f" + END_CODE.to_bytes(4, "big") if end else b"")
    result = decode_or_error(data)
    if isinstance(result, FbaError):
        check_error(result, data)


@HYP
@given(keep=st.integers(5, 60), tail=st.binary(max_size=200))
def test_valid_header_then_random_bytes(keep, tail):
    data = SMALL[:keep] + tail
    result = decode_or_error(data)
    if isinstance(result, FbaError):
        check_error(result, data)


# ---- start codes and stuffing ----------------------------------------------------------------
@pytest.mark.parametrize("data", [b"", b"\x00", b"\x00\x00\x01", b"\x00\x00\x01\xba"[:3]])
def test_empty_or_too_short(data):
    with pytest.raises(FbaError) as info:
        decode(data)
    assert info.value.bit_offset == 0
    assert len(info.value.partial) == 0
    with pytest.raises(FbaError):
        list(iter_decode(data))


def test_object_start_code_alone():
    data = OBJECT_START_CODE.to_bytes(4, "big")
    with pytest.raises(FbaError) as info:
        decode(data)
    assert info.value.bit_offset == 32 and len(info.value.partial) == 0


def test_object_start_code_then_end_code_is_an_empty_stream():
    s = decode(OBJECT_START_CODE.to_bytes(4, "big") + b"\x7f" + END_CODE.to_bytes(4, "big"))
    assert len(s) == 0


@pytest.mark.parametrize("first", [0x000001BB, 0x000001B0, 0x000001B5, 0x000001B1, 0x12345678, 0x000001BA - 1])
def test_wrong_object_start_code(first):
    data = first.to_bytes(4, "big") + SMALL[4:]
    with pytest.raises(FbaError) as info:
        decode(data)
    assert info.value.bit_offset == 0
    assert "0x%08X" % first in str(info.value)


def test_missing_object_start_code():
    with pytest.raises(FbaError) as info:
        decode(SMALL[4:])
    assert info.value.bit_offset == 0 and len(info.value.partial) == 0


def test_legacy_object_start_code_is_kept():
    data = OBJECT_START_CODE_OLD.to_bytes(4, "big") + SMALL[4:]
    s = decode(data)
    assert s.object_start_code == OBJECT_START_CODE_OLD
    assert_streams_equal(s, decode(SMALL), VALUE_FIELDS)
    assert encode(s) == data


@pytest.mark.parametrize("code", [0x000001B0, 0x000001B5, 0x000001BA, 0x00000100, 0x000001FF])
def test_unexpected_start_code_between_planes(code):
    full = decode(SMALL)
    plane = PLANE_START_CODE.to_bytes(4, "big")
    first = SMALL.index(plane)
    second = SMALL.index(plane, first + 4)  # the start code before intra frame 4
    data = SMALL[:second] + code.to_bytes(4, "big") + SMALL[second + 4:]
    with pytest.raises(FbaError) as info:
        decode(data)
    exc = info.value
    assert exc.frame == 4 and exc.bit_offset == 8 * second
    assert "0x%08X" % code in str(exc)
    check_error(exc, data, full)
    assert len(exc.partial) == 4


def test_unexpected_start_code_instead_of_end_code():
    data = SMALL[:-4] + (0x000001B0).to_bytes(4, "big")
    with pytest.raises(FbaError) as info:
        decode(data)
    assert info.value.frame == 10 and len(info.value.partial) == 10
    assert info.value.bit_offset == 8 * (len(SMALL) - 4)


def _stuffing_bit(data: bytes, code_at: int) -> int:
    """Bit offset of the '0' that starts next_start_code() stuffing before the start code at byte ``code_at``."""
    byte = data[code_at - 1]
    ones = 0
    while ones < 8 and byte & (1 << ones):
        ones += 1
    assert ones < 8, "no stuffing '0' in the byte before the start code"
    return 8 * code_at - ones - 1


@pytest.mark.parametrize("data", streams_under_test())
def test_stuffing_violation_before_end_code(data):
    full = decode(data)
    bit = _stuffing_bit(data, len(data) - 4)
    bad = bytearray(data)
    bad[bit // 8] ^= 0x80 >> (bit % 8)  # the stuffing '0' becomes a '1'
    with pytest.raises(FbaError) as info:
        decode(bytes(bad))
    exc = info.value
    assert "stuffing" in str(exc)
    assert exc.bit_offset == bit
    check_error(exc, bytes(bad), full)
    assert len(exc.partial) == len(full)


def _stream_with_whole_stuffing_byte() -> bytes:
    """A generated stream whose end code follows a whole 0x7F stuffing byte."""
    for n in range(1, 40):
        data = encode(make_stream(n, n, fap_mask=SMALL_MASK))
        if data[-5] == 0x7F:
            return data
    raise AssertionError("no generated stream ends on a byte boundary")


@pytest.mark.parametrize("byte", [0x00, 0xFF, 0x3F, 0x7E])
def test_replaced_stuffing_byte(byte):
    data = _stream_with_whole_stuffing_byte()
    n = len(decode(data))
    bad = data[:-5] + bytes([byte]) + data[-4:]
    with pytest.raises(FbaError) as info:
        decode(bad)
    exc = info.value
    assert len(exc.partial) == n
    assert "stuffing" in str(exc) and exc.bit_offset == 8 * (len(data) - 5)


def test_stuffing_violation_names_the_frame():
    data = _stream_with_whole_stuffing_byte()
    n = len(decode(data))
    with pytest.raises(FbaError) as info:
        decode(data[:-5] + b"\xff" + data[-4:])
    assert info.value.frame == n  # got None


def test_missing_stuffing_before_end_code_is_accepted_when_aligned():
    """No plane starts with 23 zeros, so an aligned end code without its 0x7F byte still ends the stream."""
    data = _stream_with_whole_stuffing_byte()
    assert_streams_equal(decode(data[:-5] + data[-4:]), decode(data))


def test_stuffing_violation_before_plane_start_code():
    full = decode(SMALL)
    at = SMALL.index(PLANE_START_CODE.to_bytes(4, "big"), 5)  # before intra frame 4
    bit = _stuffing_bit(SMALL, at)
    bad = bytearray(SMALL)
    bad[bit // 8] ^= 0x80 >> (bit % 8)
    with pytest.raises(FbaError) as info:
        decode(bytes(bad))
    assert "stuffing" in str(info.value) and info.value.bit_offset == bit
    check_error(info.value, bytes(bad), full)


# ---- DCT mode (coding_type 1) ------------------------------------------------------------------
def _coding_type_offset(mask_types, frame_start: int = 32, time_code: bool = False, skip_bits: int = 1) -> int:
    """Bit offset of a face intra header's coding_type (the header as documented in spec/SYNTAX.md)."""
    pos = frame_start + 1 + 2        # is_intra, fba_object_mask
    pos += 1 + 8 + 4 + 1             # is_frame_rate + frame_rate, seconds, frequency_offset
    pos += 1 + (18 if time_code else 0)
    pos += skip_bits                 # skip_frames flag (no count)
    pos += 5                         # fap_quant
    for t, size in zip(mask_types, GROUP_SIZES):
        pos += 1 + 2 + (size if t in (1, 2) else 0)
    return pos + 1                   # suggested_gender


def first_plane_bit(data: bytes) -> int:
    """Bit offset of the first plane: after the object start code, and after a plane start code if one follows."""
    plane_codes = (PLANE_START_CODE.to_bytes(4, "big"), PLANE_START_CODE_OLD.to_bytes(4, "big"))
    if data[5:9] in plane_codes:  # 0x7F stuffing, then the plane start code
        return 72
    if data[4:8] in plane_codes:
        return 64
    return 32


def _flip(data: bytes, bit: int) -> bytes:
    bad = bytearray(data)
    bad[bit // 8] ^= 0x80 >> (bit % 8)
    return bytes(bad)


@pytest.mark.parametrize("types", [(3,) * 10, (2, 1, 0, 3, 2, 0, 1, 3, 0, 2), (1, 0, 0, 0, 0, 0, 0, 0, 0, 0)])
def test_dct_coding_type_is_unsupported(types):
    rng = np.random.default_rng(7)
    mask = mask_from_types(rng, types)
    for (a, _), t in zip(GROUP_SLICES, types):
        if t in (1, 2):
            mask[a] = True  # at least one FAP in each per-FAP-masked group
    data = encode(make_stream(1, 3, fap_mask=mask), EncodeOptions(mask_types=types))
    assert decode(data).intra[0].face.mask_types == types
    offset = _coding_type_offset(types)
    assert data[offset // 8] & (0x80 >> (offset % 8)) == 0  # coding_type 0 where the syntax says
    with pytest.raises(UnsupportedFeature) as info:
        decode(_flip(data, offset))
    exc = info.value
    assert isinstance(exc, FbaError)
    assert exc.bit_offset == offset and exc.frame == 0 and len(exc.partial) == 0
    assert f"bit {offset}" in str(exc) and "DCT" in str(exc)


def test_dct_coding_type_in_real_vector():
    data = _vote_or_skip()
    offset = _coding_type_offset((2,) + (0,) * 9)
    with pytest.raises(UnsupportedFeature) as info:
        decode(_flip(data, offset))
    assert info.value.bit_offset == offset


def test_dct_coding_type_in_a_later_intra_frame():
    s = make_stream(2, 6, fap_mask=SMALL_MASK)
    data = encode(s, EncodeOptions(intra_period=4))
    full = decode(data)
    assert sorted(full.intra) == [0, 4]
    start = 32 + int(full.bits[:4].sum())  # no plane start codes: frames follow each other
    offset = _coding_type_offset(full.intra[4].face.mask_types, frame_start=start)
    with pytest.raises(UnsupportedFeature) as info:
        decode(_flip(data, offset))
    exc = info.value
    assert exc.bit_offset == offset and exc.frame == 4
    check_error(exc, data, full)
    assert len(exc.partial) == 4


def test_dct_coding_type_in_body_header():
    bap_mask = np.zeros(296, dtype=bool)
    bap_mask[list(spec.BAP_GROUPS[0])] = True  # BAP group 1 whole: mask types 3, 0, 0, ...
    data = encode(make_stream(4, 2, bap_mask=bap_mask), EncodeOptions(bap_quant=1))
    assert decode(data).intra[0].body.mask_types == (3,) + (0,) * 23
    offset = 32 + 3 + 14 + 1 + 1 + 5 + 24 * 3 + 1  # header, bap_quant, 24 groups, gender
    with pytest.raises(UnsupportedFeature) as info:
        decode(_flip(data, offset))
    assert info.value.bit_offset == offset


def test_encoding_dct_coding_type_is_unsupported():
    s = decode(SMALL)
    s.intra[0] = replace(s.intra[0], face=replace(s.intra[0].face, coding_type=1))
    with pytest.raises(UnsupportedFeature):
        encode(s)


# ---- planes that need an intra frame first -----------------------------------------------------
@pytest.mark.parametrize("data", streams_under_test())
def test_p_plane_before_any_intra(data):
    bad = _flip(data, first_plane_bit(data))  # is_intra of the first plane: 1 -> 0
    with pytest.raises(FbaError) as info:
        decode(bad)
    exc = info.value
    assert exc.frame == 0 and len(exc.partial) == 0
    assert "intra" in str(exc)


def test_p_plane_adds_the_body_without_intra():
    """Frame 1 of a face-only stream claims body data (fba_object_mask 01 -> 11) without an intra plane."""
    s = make_stream(5, 3, fap_mask=SMALL_MASK, hold=0.0)
    data = encode(s)
    full = decode(data)
    mask_bit = 32 + int(full.bits[0]) + 1  # first fba_object_mask bit of frame 1
    with pytest.raises(FbaError) as info:
        decode(_flip(data, mask_bit))
    exc = info.value
    assert exc.frame == 1 and len(exc.partial) == 1
    assert "body" in str(exc)
    check_error(exc, data, full)


@pytest.mark.parametrize("data", streams_under_test())
def test_object_mask_zero(data):
    bad = bytearray(data)
    for bit in (first_plane_bit(data) + 1, first_plane_bit(data) + 2):  # fba_object_mask follows is_intra
        bad[bit // 8] &= ~(0x80 >> (bit % 8)) & 0xFF
    with pytest.raises(FbaError) as info:
        decode(bytes(bad))
    assert "fba_object_mask" in str(info.value) and info.value.frame == 0


# ---- sources -----------------------------------------------------------------------------------
def test_missing_file(tmp_path):
    missing = tmp_path / "nope.fba"
    with pytest.raises(FbaError) as info:
        decode(missing)
    assert "nope.fba" in str(info.value)
    with pytest.raises(FbaError):
        decode(str(missing))
    with pytest.raises(FbaError):
        list(iter_decode(missing))


def test_file_object_and_bytes_agree(tmp_path):
    path = tmp_path / "small.fba"
    path.write_bytes(SMALL)
    with open(path, "rb") as fh:
        assert_streams_equal(decode(fh), decode(SMALL))
    assert_streams_equal(decode(bytearray(SMALL)), decode(memoryview(SMALL)))


# ---- the encoder refuses what it cannot write ---------------------------------------------------
def _bad_stream(kind: str) -> FapStream:
    s = FapStream.empty(2)
    if kind == "fap-too-big":
        s.fap_mask[:, 2] = True
        s.fap_values[:, 2] = 10**6
    elif kind == "fap-jump-too-big":
        s.fap_mask[:, 2] = True
        s.fap_values[:, 2] = [0, 8000]  # FAP 3, step 4: 2000 levels, beyond any range, as a change or an intra value
    elif kind == "viseme-select":
        s.fap_mask[:, 0] = True
        s.viseme[:, 0] = 15
    elif kind == "negative-select":
        s.fap_mask[:, 1] = True
        s.expression[:, 0] = -1
    elif kind == "expression-select":
        s.fap_mask[:, 1] = True
        s.expression[:, 2] = 7
    elif kind == "blend":
        s.fap_mask[:, 0] = True
        s.viseme[:, 2] = 200
    elif kind == "bap-too-big":
        s.object_mask[:] = 2
        s.bap_mask[:, 0] = True
        s.bap_values[:, 0] = 10**7
    elif kind == "viseme-def":
        s.fap_mask[:, 0] = True
        s.viseme[:, 3] = 2
    return s


@pytest.mark.parametrize("kind", ["fap-too-big", "fap-jump-too-big", "viseme-select", "negative-select",
                                  "expression-select", "blend", "bap-too-big", "viseme-def"])
def test_encoder_rejects_out_of_range_values(kind):
    with pytest.raises(FbaError):
        encode(_bad_stream(kind))


def test_a_jump_beyond_the_p_range_gets_an_intra_frame():
    """-7000 -> 7000 on FAP 3 (step 4) is a change of 3500 levels, beyond any P range; as an intra value
    7000 is 1750 levels, which fits, so the encoder sends frame 1 as an intra frame."""
    s = FapStream.empty(2)
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = [-7000, 7000]
    d = decode(encode(s))
    assert sorted(d.intra) == [0, 1] and d.fap_values[:, 2].tolist() == [-7000, 7000]


def test_encoder_rejects_empty_stream():
    with pytest.raises(FbaError):
        encode(FapStream.empty(0))
