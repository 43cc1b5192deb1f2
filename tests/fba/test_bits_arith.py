"""The bottom layers: BitReader/BitWriter, start-code stuffing, and the adaptive arithmetic coder."""
from __future__ import annotations

import io

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, decode, encode
from mpeg4fa.fba.arith import (MAX_FREQUENCY, MAX_ZERO_RUN, AdaptiveModel, decode_segment, encode_segment,
                               lookahead_desyncs)
from mpeg4fa.fba.bits import BitReader, BitWriter
from mpeg4fa.fba.decoder import _Decoder

from .conftest import FRAME_FIELDS, assert_streams_equal, hyp_settings, make_stream

HYP = hyp_settings(40)

fields_st = st.lists(st.integers(1, 40).flatmap(lambda n: st.tuples(st.just(n), st.integers(0, (1 << n) - 1))),
                     max_size=60)


def _write(fields) -> BitWriter:
    w = BitWriter()
    for n, v in fields:
        w.write(n, v)
    return w


# ---- BitWriter / BitReader -------------------------------------------------------------------
@HYP
@given(fields=fields_st)
def test_bit_fields_round_trip(fields):
    w = _write(fields)
    assert w.pos == sum(n for n, _ in fields)
    w.next_start_code()
    data = w.getvalue()
    r = BitReader(data)
    for n, v in fields:
        assert r.read(n) == v
    stuffing = 8 * len(data) - r.pos
    assert 1 <= stuffing <= 8
    assert r.read(stuffing) == (1 << (stuffing - 1)) - 1  # '0' then '1's
    assert not r.available(1)


@HYP
@given(fields=fields_st, chunk=st.integers(1, 5), rewinds=st.lists(st.integers(0, 14), max_size=60))
def test_file_reader_with_tiny_chunks_equals_bytes_reader(fields, chunk, rewinds):
    w = _write(fields)
    w.next_start_code()
    w.start_code(0x1B1)
    data = w.getvalue()
    a = BitReader(data)
    b = BitReader(io.BytesIO(data), chunk_bytes=chunk)
    for i, (n, _) in enumerate(fields):
        assert a.read(n) == b.read(n)
        assert a.pos == b.pos
        back = rewinds[i] if i < len(rewinds) else 0
        back = min(back, a.pos)
        a.rewind(back)
        b.rewind(back)
        assert a.read(back) == b.read(back) if back else True
    assert a.peek_start_code() == b.peek_start_code()
    code, skip = a.peek_start_code()
    assert code == 0x1B1 and 1 <= skip <= 8
    a.skip_stuffing(skip)
    b.skip_stuffing(skip)
    assert a.read(32) == b.read(32) == 0x1B1
    assert not a.available(1) and not b.available(1)


def test_file_reader_memory_stays_a_window():
    data = bytes(range(256)) * 64  # 16 KiB
    r = BitReader(io.BytesIO(data), chunk_bytes=16)
    for k in range(len(data)):
        assert r.read(8) == data[k]
        assert len(r.buf) <= 8 * 16 + 256 + 8 * 16  # one chunk, the kept look-behind, one more chunk
    assert r.pos == 8 * len(data)


@pytest.mark.parametrize("chunk", [1, 2, 3, 7])
def test_decoder_over_a_file_with_tiny_chunks(chunk):
    s = make_stream(11, 12, fap_mask=np.arange(68) < 20, bap_mask=np.arange(296) < 9)
    data = encode(s, EncodeOptions(intra_period=5, start_codes=True))
    frames = list(_Decoder(BitReader(io.BytesIO(data), chunk_bytes=chunk)).frames())
    assert_streams_equal(FapStream.from_frames(frames), decode(data), FRAME_FIELDS)


def test_reader_errors_are_fba_errors():
    r = BitReader(b"\xab")
    assert r.read(4) == 0xA
    with pytest.raises(FbaError) as info:
        r.read(5, "a test field")
    assert info.value.bit_offset == 4 and "a test field" in str(info.value)
    with pytest.raises(FbaError):
        BitReader(b"").rewind(1)
    r = BitReader(b"\xff\x00\x00\x01\xb1")
    r.read(1)
    assert r.peek_start_code() == (0x1B1, 7)
    with pytest.raises(FbaError) as info:
        r.skip_stuffing(7)  # '1111111' is not '0111111'
    assert info.value.bit_offset == 1 and "stuffing" in str(info.value)


def test_peek_start_code_accepts_aligned_code_without_stuffing():
    r = BitReader(b"\x00\x00\x01\xb1")
    assert r.peek_start_code() == (0x1B1, 0)
    r = BitReader(b"\x7f\x00\x00\x01\xbb")
    assert r.peek_start_code() == (0x1BB, 8)
    r = BitReader(b"\x12\x34\x56\x78\x9a")
    assert r.peek_start_code() is None


def test_writer_rules():
    w = BitWriter()
    w.next_start_code()
    assert w.getvalue() == b"\x7f"  # aligned: a whole stuffing byte
    w = BitWriter()
    w.write(3, 0b101)
    w.next_start_code()
    assert w.getvalue() == bytes([0b10101111])
    w = BitWriter()
    w.write(3, 1)
    with pytest.raises(ValueError):
        w.getvalue()  # not byte aligned
    with pytest.raises(ValueError):
        w.write(2, 4)
    with pytest.raises(ValueError):
        w.write(2, -1)
    w.truncate(1)
    assert w.pos == 1


# ---- adaptive models ---------------------------------------------------------------------------
def _reference_model_cum(n: int, symbols) -> list[int]:
    """The model update rule written plainly: halve ((f + 1) // 2) when the total is 16383, then count."""
    freq = [1] * n
    for s in symbols:
        if sum(freq) == MAX_FREQUENCY:
            freq = [(f + 1) // 2 for f in freq]
        freq[s] += 1
    return [sum(freq[j:]) for j in range(n + 1)]


@pytest.mark.parametrize("n, count", [(2, 20000), (5, 17000), (61, 18000), (3721, 30000)])
def test_adaptive_model_update_matches_reference(n, count):
    rng = np.random.default_rng(n)
    weights = rng.random(n) ** 4
    symbols = rng.choice(n, size=count, p=weights / weights.sum()).tolist()
    model = AdaptiveModel(n)
    for s in symbols:
        model.update(s)
        assert model.cum()[0] <= MAX_FREQUENCY
    assert model.cum().tolist() == _reference_model_cum(n, symbols)


# ---- arithmetic coder ----------------------------------------------------------------------------
model_spec_st = st.tuples(st.booleans(), st.integers(1, 4000))  # (adaptive, size)


@st.composite
def segments_st(draw):
    """Segments of (model specs, symbols) plus raw bits written between them."""
    specs = draw(st.lists(model_spec_st, min_size=1, max_size=6))
    segments = []
    for _ in range(draw(st.integers(1, 5))):
        idx = draw(st.lists(st.integers(0, len(specs) - 1), max_size=30))
        syms = [draw(st.integers(0, specs[i][1] - 1)) for i in idx]
        # skew towards the extremes of the alphabet sometimes: long runs of 0s/1s in the output
        syms = [s if draw(st.booleans()) else (specs[i][1] - 1 if draw(st.booleans()) else 0)
                for s, i in zip(syms, idx)]
        raw = draw(st.lists(st.booleans(), max_size=3))
        segments.append((idx, syms, raw))
    return specs, segments


def _models(specs):
    return [AdaptiveModel(n) if adaptive else n for adaptive, n in specs]


def _encode_segments(specs, segments, adapt):
    models = _models(specs)
    w = BitWriter()
    ends = []
    for idx, syms, raw in segments:
        ends.append(encode_segment(w, syms, [models[i] for i in idx], adapt))
        for bit in raw:
            w.write(1, int(bit))
    w.write(16, 0xFFFF)  # the decoder's 16-bit look-ahead past the last segment
    w.next_start_code()
    return w, ends, models


def _decode_segments(data, specs, segments, adapt, chunk=None):
    models = _models(specs)
    r = BitReader(data) if chunk is None else BitReader(io.BytesIO(data), chunk_bytes=chunk)
    out = []
    for idx, _, raw in segments:
        out.append(decode_segment(r, [models[i] for i in idx], adapt))
        assert [bool(r.read(1)) for _ in raw] == raw
    return out, models, r


@HYP
@given(case=segments_st(), adapt=st.booleans())
def test_segments_round_trip(case, adapt):
    specs, segments = case
    w, ends, enc_models = _encode_segments(specs, segments, adapt)
    # a segment whose trailing zeros run into the next one's bits desynchronises any decoder: the
    # encoder of planes repairs those places; here they are just skipped
    assume(not any(end.zeros >= 8 and lookahead_desyncs(w.buf, end) for end in ends))
    decoded, dec_models, _ = _decode_segments(w.getvalue(), specs, segments, adapt)
    assert decoded == [syms for _, syms, _ in segments]
    assert _decode_segments(w.getvalue(), specs, segments, adapt, chunk=1)[0] == decoded
    for a, b in zip(enc_models, dec_models):  # both sides adapted their models the same way
        if isinstance(a, AdaptiveModel):
            assert a.cum().tolist() == b.cum().tolist()


def test_model_halving_over_many_segments():
    """20,000 symbols into one adaptive model, over 20 segments: the 16,383 total is passed and halved."""
    rng = np.random.default_rng(2024)
    n = 9
    symbols = rng.choice(n, size=20000, p=[0.5, 0.2, 0.1, 0.08, 0.05, 0.03, 0.02, 0.015, 0.005]).tolist()
    chunks = [symbols[i:i + 1000] for i in range(0, len(symbols), 1000)]
    enc_model, dec_model = AdaptiveModel(n), AdaptiveModel(n)
    w = BitWriter()
    ends = []
    for chunk in chunks:
        ends.append(encode_segment(w, chunk, [enc_model] * len(chunk), True))
    w.write(16, 0xFFFF)
    w.next_start_code()
    assert not any(end.zeros >= 8 and lookahead_desyncs(w.buf, end) for end in ends)
    r = BitReader(w.getvalue())
    for chunk in chunks:
        assert decode_segment(r, [dec_model] * len(chunk), True) == chunk
    cum = enc_model.cum()
    assert cum.tolist() == dec_model.cum().tolist() == _reference_model_cum(n, symbols)
    assert cum[0] <= MAX_FREQUENCY < len(symbols) + n  # so the counts were halved on the way
    # adaptation pays: far fewer bits than a uniform code (log2(9) = 3.17 bits a symbol)
    assert len(w.buf) < 2.6 * len(symbols)


def _longest_zero_run(bits) -> int:
    best = run = 0
    for b in bits:
        run = run + 1 if b == 0 else 0
        best = max(best, run)
    return best


@pytest.mark.parametrize("adaptive", [False, True])
def test_improbable_symbols_are_stuffed(adaptive):
    """Symbols at the bottom of the interval write long runs of zeros; a '1' follows every 22."""
    n = 4000
    symbols = [n - 1] * 200  # the last symbol: the lowest, narrowest slice of the interval
    models = [AdaptiveModel(n) if adaptive else n for _ in symbols]
    w = BitWriter()
    end = encode_segment(w, symbols, models, adapt=True)
    bits = bytes(w.buf)
    assert _longest_zero_run(bits) == MAX_ZERO_RUN
    assert b"\x00" * MAX_ZERO_RUN + b"\x01" in bits  # stuffing happened
    assert end.pos == len(bits)
    w.write(16, 0xFFFF)
    w.next_start_code()
    assert not lookahead_desyncs(w.buf, end)
    data = w.getvalue()
    # no start code prefix (23 zeros and a one) anywhere in the segment's bytes
    assert b"\x00\x00\x01" not in data[: end.pos // 8]
    r = BitReader(data)
    decoded = decode_segment(r, [AdaptiveModel(n) if adaptive else n for _ in symbols], True)
    assert decoded == symbols
    assert r.pos == end.pos


def test_decoder_rejects_a_zero_where_stuffing_belongs():
    bits = bytes(30) + b"\x01" * 10  # 30 zeros: the 23rd bit must be a stuffed '1'
    w = BitWriter()
    w.buf.extend(bits)
    w.next_start_code()
    with pytest.raises(FbaError) as info:
        decode_segment(BitReader(w.getvalue()), [16] * 5, False)
    assert info.value.bit_offset == MAX_ZERO_RUN and "stuffing" in str(info.value)


def test_decoder_reports_a_segment_cut_short():
    w = BitWriter()
    encode_segment(w, [3, 1, 4, 1, 5], [7] * 5, False)
    w.next_start_code()
    data = w.getvalue()  # fewer than the 14 look-ahead bits after the flush
    with pytest.raises(FbaError) as info:
        decode_segment(BitReader(data[:1]), [7] * 5, False)
    assert "ends inside" in str(info.value)
