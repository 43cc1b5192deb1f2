"""One definition of what a decoder shows, checked as properties over random streams.

* encode -> decode -> :func:`resolve` equals the source's :func:`resolve` within half a
  quantiser step, for random masks, random intended mask types (hold / interpolate) and
  random :class:`EncodeOptions`: a stream keeps its meaning under any coding;
* :func:`fold_symmetric` leaves out only FAPs whose stream still decodes the same;
* ``face.deform(stream.frame(k))`` is ``list(face.animate(stream))[k]``.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from mpeg4fa.decoded import resolve
from mpeg4fa.fba import EncodeOptions, decode, encode
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec import EXPRESSION_PROFILES, FAP_GROUP_SLICES, FAP_PARTNERS, N_FAPS, QUANT_STEP, VISEME_PROFILES
from mpeg4fa.speech.encoder import fold_symmetric

pytestmark = pytest.mark.filterwarnings("ignore::mpeg4fa.decoded.ClampWarning")

_STEP = np.asarray(QUANT_STEP, dtype=np.float64)
_VISEMES = np.stack(list(VISEME_PROFILES["mpeg4"].values()))
_EXPRESSIONS = np.stack(list(EXPRESSION_PROFILES.values()))
# the most a one-unit error of a blend or intensity moves each FAP (profiles are at 63)
_HIGH_PER_UNIT = ((_VISEMES.max(axis=0) - _VISEMES.min(axis=0)) + 2 * np.abs(_EXPRESSIONS).max(axis=0)) / 63.0


def random_stream(rng: np.random.Generator, n: int, high_level: bool, symmetric: bool = False) -> FapStream:
    """A stream of ``n`` frames in up to three pieces, each with its own FAP mask, and an intended
    mask type per group; values move smoothly (as real streams do) inside what the codec carries."""
    stream = FapStream.empty(n)
    stream.source_fps = 25.0
    stream.timestamps[:] = np.arange(n) / 25.0
    cuts = sorted(set(rng.integers(1, n, size=rng.integers(0, 3)).tolist())) if n > 1 else []
    walk = np.cumsum(rng.integers(-40, 41, size=(n, N_FAPS)), axis=0).clip(-400, 400)
    if symmetric:  # right sides and outer lips copy their counterparts, as speech does
        for c in range(N_FAPS - 1, 1, -1):
            p = next((int(p) for p in FAP_PARTNERS[c] if 0 <= p < c), None)
            if p is not None and rng.random() < 0.7:
                walk[:, c] = walk[:, p]
    for a, b in zip([0, *cuts], [*cuts, n]):
        mask = rng.random(N_FAPS) < rng.choice([0.2, 0.5, 0.9])
        mask[:2] = False
        stream.fap_mask[a:b] = mask
    stream.fap_values[:] = np.where(stream.fap_mask, walk, 0)
    stream.mask_types = tuple(int(t) for t in rng.integers(1, 3, size=len(FAP_GROUP_SLICES)))
    if high_level:
        stream.fap_mask[:, 0] = stream.fap_mask[:, 1] = True
        stream.viseme[:, 0] = rng.integers(0, 15, n)
        stream.viseme[:, 1] = rng.integers(0, 15, n)
        stream.viseme[:, 2] = rng.integers(0, 64, n)
        stream.expression[:, 0] = rng.integers(0, 7, n)
        stream.expression[:, 1] = rng.integers(0, 64, n)
        stream.expression[:, 2] = rng.integers(0, 7, n)
        stream.expression[:, 3] = rng.integers(0, 64, n)
    return stream


def random_options(rng: np.random.Generator) -> EncodeOptions:
    return EncodeOptions(fap_quant=int(rng.choice([0, 1, 2, 3, 5, 8])), intra_period=int(rng.integers(0, 8)),
                         optimize=bool(rng.random() < 0.5), skip_repeats=bool(rng.random() < 0.3),
                         start_codes=bool(rng.random() < 0.3))


def on_source_frames(stream: FapStream) -> np.ndarray:
    """Resolved values with skipped frames shown again (what a player shows on the frame grid)."""
    return np.repeat(resolve(stream), stream.skip + 1, axis=0)


def tolerance(quant: int) -> np.ndarray:
    """Half a quantiser step per FAP: of the FAP itself, and of a blend or intensity through the profiles."""
    return quant / 2.0 * (_STEP + _HIGH_PER_UNIT) + 1e-9


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 40), high_level=st.booleans())
def test_any_coding_keeps_what_a_stream_shows(seed, n, high_level):
    rng = np.random.default_rng(seed)
    source = random_stream(rng, n, high_level)
    options = random_options(rng)
    decoded = decode(encode(source, options))
    shown, meant = on_source_frames(decoded), resolve(source)
    assert shown.shape == meant.shape
    excess = np.abs(shown - meant) - tolerance(options.fap_quant)
    assert excess.max() <= 0, f"frame/FAP {np.unravel_index(excess.argmax(), excess.shape)} off by {excess.max():g}"


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 30), high_level=st.booleans())
def test_folding_leaves_out_only_what_decodes_the_same(seed, n, high_level):
    rng = np.random.default_rng(seed)
    source = random_stream(rng, n, high_level, symmetric=True)
    source.mask_types = None  # as the text encoder makes it: hold, before folding
    meant = resolve(source)
    folded = source.copy()
    groups = fold_symmetric(folded)
    assert np.array_equal(resolve(folded), meant)
    assert folded.fap_mask.sum() <= source.fap_mask.sum()
    for g in groups:
        assert folded.mask_types[g - 1] == 2
    options = random_options(rng)
    decoded = decode(encode(folded, options))
    excess = np.abs(on_source_frames(decoded) - meant) - tolerance(options.fap_quant)
    assert excess.max() <= 0


def test_folding_finds_the_symmetric_faps():
    rng = np.random.default_rng(7)
    source = random_stream(rng, 20, False, symmetric=True)
    source.fap_mask[:] = True
    source.fap_mask[:, :2] = False
    walk = np.cumsum(rng.integers(-30, 31, size=(20, N_FAPS)), axis=0)
    walk[:, 51 - 1] = walk[:, 4 - 1]  # an outer lip that copies its inner one
    walk[:, 32 - 1] = walk[:, 31 - 1]  # raise_r_i_eyebrow = raise_l_i_eyebrow
    source.fap_values[:] = walk
    source.mask_types = None
    folded = source.copy()
    groups = fold_symmetric(folded)
    assert not folded.fap_mask[:, 32 - 1].any() and folded.fap_mask[:, 31 - 1].all()
    assert groups and np.array_equal(resolve(folded), resolve(source))


def test_a_never_sent_fap_keeps_its_group_from_interpolating():
    """An unsent FAP whose counterpart moves would copy it under interpolation: the group must hold."""
    s = FapStream.empty(5)
    s.source_fps = 25.0
    s.fap_mask[:, [56 - 1, 9 - 1, 10 - 1]] = True  # raise_b_lip_rm_o's partner, and an inner pair
    s.fap_values[:, 56 - 1] = [0, 40, 80, 40, 0]    # 57 (raise_b_lip_lm_o) is never sent and stays 0
    s.fap_values[:, 9 - 1] = s.fap_values[:, 10 - 1] = [0, 10, 20, 10, 0]
    meant = resolve(s)
    folded = s.copy()
    fold_symmetric(folded)
    assert np.array_equal(resolve(folded), meant)
    assert not resolve(folded)[:, 57 - 1].any()


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                 HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2**32 - 1), high_level=st.booleans())
def test_a_frame_of_a_stream_poses_as_the_stream_does(procedural_face, seed, high_level):
    rng = np.random.default_rng(seed)
    stream = decode(encode(random_stream(rng, 8, high_level), random_options(rng)))
    animated = [pose.vertices for pose in procedural_face.animate(stream)]
    for k in range(len(stream)):
        np.testing.assert_allclose(procedural_face.deform(stream.frame(k)).vertices, animated[k], atol=1e-9)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 30), high_level=st.booleans())
def test_explicit_streams_show_the_same_and_survive_fap_text(tmp_path_factory, seed, n, high_level):
    """A .fap has no mask types: what a decoder copies under interpolation is written out, not lost."""
    from mpeg4fa.decoded import explicit
    from mpeg4fa.formats import read_fap, write_fap

    rng = np.random.default_rng(seed)
    stream = decode(encode(random_stream(rng, n, high_level, symmetric=True), random_options(rng)))
    meant = on_source_frames(stream)
    assert np.array_equal(on_source_frames(explicit(stream)), meant)
    path = tmp_path_factory.mktemp("fap") / "s.fap"
    write_fap(stream, path)
    assert np.array_equal(on_source_frames(read_fap(path)), meant)
