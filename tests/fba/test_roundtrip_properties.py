"""encode -> decode round trips of generated FAP/BAP streams (hypothesis).

Every round trip also checks that re-encoding the decoded stream with its own parameters gives
the same bytes.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, decode, encode
from mpeg4fa.fba.stream import PLANE_START_CODE

from .conftest import (GROUP_SLICES, assert_close_to_input, assert_same_on_grid, expected_timestamps, hyp_settings,
                       make_stream, mask_from_types, mask_types_st, seeds)

FAST = hyp_settings(12)
TINY = hyp_settings(4)

frames_st = st.integers(1, 10)


def roundtrip(s: FapStream, options: EncodeOptions | None = None) -> tuple[bytes, FapStream]:
    data = encode(s, options)
    d = decode(data)
    assert encode(d) == data, "re-encoding the decoded stream changed the bytes"
    return data, d


def random_face_mask(seed: int, density: float = 0.5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.random(68) < density


def random_body_mask(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed ^ 0x5A5A)
    mask = rng.random(296) < rng.choice([0.05, 0.3, 1.0])
    if not mask.any():
        mask[rng.integers(296)] = True
    return mask


# ---- quantisers ---------------------------------------------------------------------------
@pytest.mark.parametrize("fap_quant", range(32))
@TINY
@given(seed=seeds, n=frames_st, period=st.sampled_from([None, 0, 3]))
def test_every_fap_quant(fap_quant, seed, n, period):
    s = make_stream(seed, n, fap_mask=random_face_mask(seed), fap_quant=fap_quant)
    _, d = roundtrip(s, EncodeOptions(fap_quant=fap_quant, intra_period=period))
    assert all(p.face.quant == fap_quant for p in d.intra.values())
    assert_close_to_input(d, s, fap_quant, 1)


@pytest.mark.parametrize("bap_quant", [0, 1, 2, 7, 18, 31])
@TINY
@given(seed=seeds, n=frames_st)
def test_bap_quants(bap_quant, seed, n):
    s = make_stream(seed, n, bap_mask=random_body_mask(seed), bap_quant=bap_quant)
    _, d = roundtrip(s, EncodeOptions(bap_quant=bap_quant))
    assert d.intra[0].body.quant == bap_quant and d.intra[0].face is None
    assert_close_to_input(d, s, 1, bap_quant)


def test_blend_may_exceed_63_by_less_than_half_a_step():
    s = FapStream.empty(2)
    s.fap_mask[:, 0] = True
    s.viseme[:] = [[1, 2, 63, 0], [3, 4, 63, 1]]
    _, d = roundtrip(s, EncodeOptions(fap_quant=2))
    assert d.viseme[:, 2].tolist() == [64, 64]
    assert d.viseme[:, [0, 1, 3]].tolist() == [[1, 2, 0], [3, 4, 1]]


# ---- masks --------------------------------------------------------------------------------
@FAST
@given(seed=seeds, n=frames_st, types=mask_types_st, fap_quant=st.integers(0, 31))
def test_mask_types(seed, n, types, fap_quant):
    mask = mask_from_types(np.random.default_rng(seed), types)
    s = make_stream(seed, n, fap_mask=mask, fap_quant=fap_quant)
    _, d = roundtrip(s, EncodeOptions(fap_quant=fap_quant, mask_types=types))
    assert d.intra[0].face.mask_types == tuple(types)
    np.testing.assert_array_equal(d.fap_mask, s.fap_mask)
    assert_close_to_input(d, s, fap_quant, 1)


@pytest.mark.parametrize("bad_type, fill", [(0, True), (3, False)])
def test_mask_type_must_match_data(bad_type, fill):
    """Types 0 (none) and 3 (all) must agree with the FAPs present; the encoder says so."""
    mask = np.zeros(68, dtype=bool)
    a, b = GROUP_SLICES[1]
    mask[a] = fill  # one FAP of group 2 (type 0: present; type 3: not all present)
    s = make_stream(1, 3, fap_mask=mask)
    types = [0] * 10
    types[1] = bad_type
    with pytest.raises(FbaError):
        encode(s, EncodeOptions(mask_types=types))


@pytest.mark.parametrize("kind", ["fap1", "fap2", "fap12", "face", "body", "face+body", "empty-face"])
@FAST
@given(seed=seeds, n=frames_st, fap_quant=st.integers(0, 31), bap_quant=st.integers(0, 31))
def test_parts(kind, seed, n, fap_quant, bap_quant):
    fap_mask = bap_mask = None
    if kind == "fap1":
        fap_mask = np.zeros(68, dtype=bool)
        fap_mask[0] = True
    elif kind == "fap2":
        fap_mask = np.zeros(68, dtype=bool)
        fap_mask[1] = True
    elif kind == "fap12":
        fap_mask = np.zeros(68, dtype=bool)
        fap_mask[:2] = True
    elif kind == "empty-face":
        fap_mask = np.zeros(68, dtype=bool)
    if kind in ("face", "face+body"):
        fap_mask = random_face_mask(seed)
    if kind in ("body", "face+body"):
        bap_mask = random_body_mask(seed)
    s = make_stream(seed, n, fap_mask=fap_mask, bap_mask=bap_mask, fap_quant=fap_quant, bap_quant=bap_quant)
    _, d = roundtrip(s, EncodeOptions(fap_quant=fap_quant, bap_quant=bap_quant))
    np.testing.assert_array_equal(d.object_mask, s.object_mask)
    first = d.intra[0]
    assert (first.face is not None) == (fap_mask is not None)
    assert (first.body is not None) == (bap_mask is not None)
    assert_close_to_input(d, s, fap_quant, bap_quant)


@FAST
@given(seed=seeds, n=st.integers(2, 10), change=st.integers(1, 9), body_joins=st.booleans(),
       optimize=st.booleans())
def test_mask_and_object_changes_start_intra_frames(seed, n, change, body_joins, optimize):
    """A FAP mask change (and the body joining the face) starts an intra frame.

    Both the default encoding and ``optimize`` get any mask change (FAPs lost or gained, a body joining).
    """
    change = min(change, n - 1)
    s = make_stream(seed, n, fap_mask=random_face_mask(seed), bap_mask=random_body_mask(seed), hold=0.0)
    other = random_face_mask(seed + 1)
    s.fap_mask[change:] = other
    s.fap_values[change:, ~other] = 0
    s.viseme[change:, :] *= other[0]
    s.expression[change:, :] *= other[1]
    if body_joins:  # face only until `change`, then face and body
        s.object_mask[:change] = 1
        s.bap_mask[:change] = False
        s.bap_values[:change] = 0
    _, d = roundtrip(s, EncodeOptions(optimize=optimize))
    if body_joins or not np.array_equal(s.fap_mask[change - 1], other):
        assert change in d.intra
    np.testing.assert_array_equal(d.object_mask, s.object_mask)
    assert_close_to_input(d, s, 1, 1)


def test_fap_first_masked_after_a_mask_change():
    s = FapStream.empty(2)
    s.fap_mask[0, 2] = True  # FAP 3 in frame 0
    s.fap_values[0, 2] = 40
    s.fap_mask[1, 3] = True  # FAP 4 only from frame 1 (an intra frame: the mask changed)
    s.fap_values[1, 3] = 100
    d = decode(encode(s))  # FbaError: FAP 4: intra value 100 ... outside its coded range 0..0
    assert d.fap_values[:, 2:4].tolist() == [[40, 0], [0, 100]]


def test_body_joining_a_face_stream():
    s = FapStream.empty(2)
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = 40
    s.object_mask[1] = 3  # the body joins at frame 1
    s.bap_mask[1, 0] = True
    s.bap_values[1, 0] = 1700
    d = decode(encode(s))  # FbaError: BAP 1: intra value 1700 ... outside its coded range 0..0
    assert d.bap_values[:, 0].tolist() == [0, 1700]


def test_fap_first_masked_after_a_mask_change_with_optimize():
    s = FapStream.empty(2)
    s.fap_mask[0, 2] = True
    s.fap_values[0, 2] = 40
    s.fap_mask[1, 3] = True
    s.fap_values[1, 3] = 100
    _, d = roundtrip(s, EncodeOptions(optimize=True))
    assert sorted(d.intra) == [0, 1]
    assert d.fap_values[:, 2:4].tolist() == [[40, 0], [0, 100]]


# ---- timing: skips, frame rates, time codes -------------------------------------------------
skips_st = st.lists(st.sampled_from([0, 0, 0, 1, 2, 14, 15, 16, 29, 30, 31, 44, 45, 100]), min_size=1, max_size=10)


@FAST
@given(seed=seeds, skips=skips_st, fps=st.sampled_from([25.0, 30.0, 29.97, 12.5, 10.0, 60.0]),
       period=st.sampled_from([None, 2]))
def test_skips_survive(seed, skips, fps, period):
    n = len(skips)
    s = make_stream(seed, n, fap_mask=random_face_mask(seed, 0.3), fps=fps)
    s.skip[:] = skips
    _, d = roundtrip(s, EncodeOptions(fps=fps, intra_period=period))
    np.testing.assert_array_equal(d.skip, skips)
    assert abs(d.fps - fps) < 1 / 32
    np.testing.assert_allclose(d.timestamps, expected_timestamps(d.skip, d.fps), rtol=0, atol=1e-6)
    assert_close_to_input(d, s, 1, 1)


@FAST
@given(seed=seeds, seconds=st.integers(1, 3), extra=st.integers(0, 24), t0=st.integers(0, 20000),
       period=st.sampled_from([25, 10]))
def test_time_codes(seed, seconds, extra, t0, period):
    """Intra frames on whole seconds carry a time code and decode to that time; other intra frames carry none."""
    fps = 25.0
    n = 25 * seconds + extra
    s = make_stream(seed, n, fap_mask=random_face_mask(seed, 0.1), fps=fps, hold=0.0)
    s.timestamps[:] = t0 + np.arange(n) / fps
    _, d = roundtrip(s, EncodeOptions(fps=fps, intra_period=period, time_codes=True))
    assert set(range(0, n, period)) <= set(d.intra)
    for k, params in d.intra.items():
        if k % 25 == 0:
            assert params.time_code is not None and params.time_code.total_seconds == t0 + k // 25
            assert d.timestamps[k] == t0 + k // 25
        else:
            assert params.time_code is None
    np.testing.assert_allclose(d.timestamps, t0 + np.arange(n) / fps, rtol=0, atol=1e-6)
    assert_close_to_input(d, s, 1, 1)


@FAST
@given(seed=seeds, n=st.integers(1, 14), period=st.integers(1, 6), start_codes=st.booleans())
def test_intra_period_and_start_codes(seed, n, period, start_codes):
    s = make_stream(seed, n, fap_mask=random_face_mask(seed), bap_mask=random_body_mask(seed))
    data, d = roundtrip(s, EncodeOptions(intra_period=period, start_codes=start_codes))
    intra = sorted(d.intra)
    assert set(range(0, n, period)) <= set(intra)
    if start_codes:
        assert (d.start_code[intra] == PLANE_START_CODE).all()
        assert data.count(PLANE_START_CODE.to_bytes(4, "big")) == len(intra)
    else:
        assert not d.start_code.any()
    assert not d.start_code[[k for k in range(n) if k not in d.intra]].any()
    assert_close_to_input(d, s, 1, 1)


@FAST
@given(seed=seeds, n=st.integers(2, 10), fap_quant=st.integers(0, 31))
def test_skip_repeats_folds_equal_frames(seed, n, fap_quant):
    s = make_stream(seed, n, fap_mask=random_face_mask(seed), fap_quant=fap_quant, hold=0.5)
    _, plain = roundtrip(s, EncodeOptions(fap_quant=fap_quant))
    _, folded = roundtrip(s, EncodeOptions(fap_quant=fap_quant, skip_repeats=True))
    distinct = 1 + sum(
        not (np.array_equal(s.fap_values[k], s.fap_values[k - 1]) and np.array_equal(s.viseme[k], s.viseme[k - 1])
             and np.array_equal(s.expression[k], s.expression[k - 1])) for k in range(1, n))
    assert len(folded) == distinct
    assert int((folded.skip + 1).sum()) == n
    assert_same_on_grid(folded, plain)


@pytest.mark.parametrize("option", ["skip_repeats", "optimize"])
def test_fold_repeats_on_a_single_frame(option):
    s = FapStream.empty(1)
    s.fap_mask[0, 2] = True
    s.fap_values[0, 2] = 10
    _, d = roundtrip(s, EncodeOptions(**{option: True}))
    assert abs(int(d.fap_values[0, 2]) - 10) <= 4 // 2 and d.skip.tolist() == [0]  # FAP 3: qstep 4 at quant 1


# ---- optimize ------------------------------------------------------------------------------
@FAST
@given(seed=seeds, n=st.integers(2, 12), fap_quant=st.integers(0, 31), bap_quant=st.integers(0, 31),
       body=st.booleans(), skips=st.booleans(), hold=st.sampled_from([0.0, 0.3, 0.8]),
       period=st.sampled_from([None, 2, 3]))
def test_optimize_keeps_values_and_is_never_larger(seed, n, fap_quant, bap_quant, body, skips, hold, period):
    s = make_stream(seed, n, fap_mask=random_face_mask(seed), fap_quant=fap_quant,
                    bap_mask=random_body_mask(seed) if body else None, bap_quant=bap_quant, hold=hold)
    if skips:
        s.skip[:] = np.random.default_rng(seed).integers(0, 20, n)
    options = dict(fap_quant=fap_quant, bap_quant=bap_quant, intra_period=period)
    default, d_default = roundtrip(s, EncodeOptions(**options))
    optimized, d_opt = roundtrip(s, EncodeOptions(optimize=True, **options))
    assert len(optimized) <= len(default)
    assert_same_on_grid(d_opt, d_default)
    assert_close_to_input(d_opt, s, fap_quant, bap_quant)


@FAST
@given(seed=seeds, n=st.integers(2, 12), period=st.integers(1, 5))
def test_optimize_with_intra_period_stays_within_half_a_step(seed, n, period):
    s = make_stream(seed, n, fap_mask=random_face_mask(seed), hold=0.4)
    default, _ = roundtrip(s, EncodeOptions(intra_period=period))
    optimized, d_opt = roundtrip(s, EncodeOptions(intra_period=period, optimize=True))
    assert len(optimized) <= len(default)
    assert_close_to_input(d_opt, s, 1, 1)


def test_optimize_with_intra_period_keeps_default_values():
    """FAP 4 (step 2 at fap_quant 1), values 2, 2, 1, intra_period 2: a quantiser tie at frame 2.

    Default: frames 0 and 2 are intra; frame 2 decodes to quantise(1, 2) = 0. optimize folds frame 1
    into frame 0's skip; it must still make grid frame 2 the intra frame (a P frame predicted from 2
    would quantise the change -1 to 0 and decode to 2).
    """
    s = FapStream.empty(3)
    s.fap_mask[:, 3] = True
    s.fap_values[:, 3] = [2, 2, 1]
    options = dict(fap_quant=1, intra_period=2)
    d_default = decode(encode(s, EncodeOptions(**options)))
    d_opt = decode(encode(s, EncodeOptions(optimize=True, **options)))
    assert d_default.fap_values[:, 3].tolist() == [2, 2, 0]
    assert_same_on_grid(d_opt, d_default)


# ---- repairs -------------------------------------------------------------------------------
REPAIR_FAPS = [4, 5, 7, 8, 9, 10, 13, 20, 23, 28, 31, 36, 38, 48, 49, 50, 51, 54, 61, 62, 65, 67]
REPAIR_VALUES = [
    [500, 690, 0, -181, -1170, -432, 0, -129, -29977, -125, 89, 0, 0, 77700, -39081, 50099, -221, 258, 368, -141,
     269, 298],
    [-946, -83, -1172, -1613, 180, 99, 0, 890, 0, -143, 0, 0, 0, 69299, 0, 62899, 0, -1186, 0, 0, 0, 0],
    [0, -83, -1172, -807, 0, 0, -30, 0, 0, 0, 599, 0, 799, 138500, 0, 0, -661, 0, 0, -300, 449, 0],
]


def test_repair_intra_frame_gets_ranges_that_fit():
    s = FapStream.empty(3)
    cols = [f - 1 for f in REPAIR_FAPS]
    s.fap_mask[:, cols] = True
    s.fap_values[:, cols] = REPAIR_VALUES
    _, d = roundtrip(s, EncodeOptions(fap_quant=15))  # FbaError, frame 2
    assert_close_to_input(d, s, 15, 1)
