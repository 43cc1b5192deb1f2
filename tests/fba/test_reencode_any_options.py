"""Any decodable stream re-encodes with any intra period and quantiser the syntax can express (issue 14, item 4).

Intra frames move to where their values fit a range code, and are added where a change would not;
what no stream can carry (e.g. large angles with fap_quant 0, which sends values unquantised) is one
FbaError that names the FAP, the value and the limit.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, decode, encode

from .conftest import SKIP_REASON, assert_close_to_input, hyp_settings, real_vector_paths

PERIODS = (1, 25, 250)
QUANTS = (0, 1, 2, 8, 31)


def reencode(stream: FapStream, period: int, quant: int) -> FapStream | FbaError:
    try:
        data = encode(stream, EncodeOptions(intra_period=period, fap_quant=quant, bap_quant=quant))
    except FbaError as exc:
        return exc
    decoded = decode(data)
    assert_close_to_input(decoded, stream, quant, quant)
    return decoded


def assert_honest_refusal(exc: FbaError, quant: int) -> None:
    """A refusal names the parameter and value and the largest range, and only happens unquantised
    (at fap_quant >= 1 every value a decoder can decode fits: |v| <= 1860 x its step)."""
    assert quant == 0, exc
    assert exc.message.startswith(("FAP ", "BAP ")) and "beyond the largest range 31*60/1 = 1860" in exc.message
    assert "fap_quant 1 or more" in exc.hint or "bap_quant 1 or more" in exc.hint


@pytest.mark.skipif(not real_vector_paths(), reason=SKIP_REASON)
@hyp_settings(25)
@given(index=st.integers(0, 10 ** 6), period=st.sampled_from(PERIODS), quant=st.sampled_from(QUANTS))
def test_real_streams_reencode_with_any_period_and_quantiser(index, period, quant):
    paths = real_vector_paths()
    result = reencode(decode(paths[index % len(paths)]), period, quant)
    if isinstance(result, FbaError):
        assert_honest_refusal(result, quant)


def test_the_issue_case_headmotion_long_intra_every_frame():
    paths = [p for p in real_vector_paths() if p.name == "headmotion_long.fba"]
    if not paths:
        pytest.skip(SKIP_REASON)
    s = decode(paths[0])  # FAP 19 reaches 2009 (step 1): more than an intra value can hold at fap_quant 1
    for period in (1, 250):
        d = reencode(s, period, 1)
        assert isinstance(d, FapStream)
    assert len(reencode(s, 1, 1).intra) < len(s)  # frames whose values do not fit an intra header stay P frames


def jumpy(n: int = 40) -> FapStream:
    """FAP 19 (step 1) climbs past what an intra value can hold, and FAP 3 jumps by more than a P range."""
    s = FapStream.empty(n)
    s.fap_mask[:, [2, 18]] = True
    s.fap_values[:, 18] = np.minimum(np.arange(n) * 150, 5000)   # 0 .. 5000 FAPU, in steps of 150
    s.fap_values[:, 2] = np.where(np.arange(n) % 10 < 5, 0, 1500)  # open_jaw jumps 0 <-> 1500 (step 4)
    return s


@pytest.mark.parametrize("period", [0, 1, 5, 25])
@pytest.mark.parametrize("quant", [1, 2, 8])
def test_intra_frames_move_and_are_added_as_needed(period, quant):
    s = jumpy()
    d = reencode(s, period, quant)
    assert isinstance(d, FapStream)
    fit = 31 * 60 // quant
    for k in d.intra:  # every intra frame can carry its values
        assert abs(int(d.fap_values[k, 18])) // quant <= fit


def test_what_no_stream_can_carry_is_one_clear_error():
    s = jumpy()
    s.fap_values[:, 2] *= 2  # unquantised, a jump of 3000 fits neither a P range nor an intra value
    exc = reencode(s, 5, 0)
    assert isinstance(exc, FbaError)
    assert_honest_refusal(exc, 0)
    assert exc.message.startswith("FAP 3 = 3000: the change from the previous frame needs level 3000")
    assert exc.frame == 5
    assert isinstance(reencode(s, 5, 2), FapStream)  # the hint holds: quantised, it fits


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_both_paths_place_intra_frames_alike(backend):
    s = jumpy(60)
    ref = encode(s, EncodeOptions(intra_period=7, fap_quant=2), backend="python")
    assert encode(s, EncodeOptions(intra_period=7, fap_quant=2), backend=backend) == ref
