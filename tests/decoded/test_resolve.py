"""Stream resolution: the 68 FAP values a face shows at every frame of a FapStream.

Hold (unsent FAPs keep their value), mask type 2 interpolation (left <-> right and
inner <-> outer lip counterparts sent in the same frame), and the high-level
FAPs 1 and 2 expanded through the shared profiles, with sent low-level FAPs
taking precedence.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.decoded import resolve
from mpeg4fa.spec import FAP_PARTNERS as PARTNERS
from mpeg4fa.fba.stream import CodingParams, FapStream, PartParams
from mpeg4fa.spec import FAP_GROUP, N_FAPS, expand_high_level

HOLD, INTERPOLATE = 1, 2
# random streams carry values no face shows; the clamp tests below check that warning on their own
pytestmark = pytest.mark.filterwarnings("ignore::mpeg4fa.face.errors.FaceWarning")


def _intra(types: dict[int, int] | int = HOLD) -> CodingParams:
    """An intra header whose face part gives each FAP group a mask type (1 by default)."""
    per_group = [HOLD] * 10
    if isinstance(types, int):
        per_group = [types] * 10
    else:
        for group, t in types.items():
            per_group[group - 1] = t
    return CodingParams(face=PartParams(quant=1, mask_types=tuple(per_group), mask=np.ones(N_FAPS, bool)))


def _send(stream: FapStream, frame: int, values: dict[int, int]) -> None:
    for fap, value in values.items():
        stream.fap_mask[frame, fap - 1] = True
        stream.fap_values[frame, fap - 1] = value


def _group(fap: int) -> int:
    return int(FAP_GROUP[fap - 1])


def test_empty_and_unsent():
    assert resolve(FapStream.empty(0)).shape == (0, N_FAPS)
    out = resolve(FapStream.empty(4))
    assert out.shape == (4, N_FAPS) and not out.any()


def test_hold_keeps_the_last_sent_value():
    s = FapStream.empty(6)
    s.intra[0] = _intra(HOLD)
    _send(s, 1, {4: 50, 19: 300})
    _send(s, 3, {4: -20})
    _send(s, 4, {19: 0})
    out = resolve(s)
    assert out[:, 3].tolist() == [0, 50, 50, -20, -20, -20]
    assert out[:, 18].tolist() == [0, 300, 300, 300, 0, 0]
    untouched = np.ones(N_FAPS, bool)
    untouched[[3, 18]] = False
    assert not out[:, untouched].any()


def test_hold_without_any_intra_header():
    s = FapStream.empty(3)
    _send(s, 0, {48: 1000})
    assert resolve(s)[:, 47].tolist() == [1000, 1000, 1000]


def test_partners_table():
    assert PARTNERS[6 - 1, 0] == 7 - 1 and PARTNERS[7 - 1, 0] == 6 - 1  # stretch corner l/r
    assert PARTNERS[19 - 1, 0] == 20 - 1  # eyelids
    assert PARTNERS[4 - 1, 1] == 51 - 1 and PARTNERS[51 - 1, 1] == 4 - 1  # inner/outer lip
    assert PARTNERS[53 - 1, 0] == 54 - 1 and PARTNERS[53 - 1, 1] == 6 - 1
    assert PARTNERS[3 - 1].tolist() == [-1, -1]  # open_jaw has no counterpart


def test_type2_copies_left_right_in_the_same_frame():
    s = FapStream.empty(3)
    s.intra[0] = _intra({_group(6): INTERPOLATE, _group(19): INTERPOLATE})
    _send(s, 0, {6: 30, 20: 500})
    _send(s, 2, {7: -12})
    out = resolve(s)
    assert out[0, 7 - 1] == 30 and out[0, 6 - 1] == 30
    assert out[0, 19 - 1] == 500 and out[0, 20 - 1] == 500
    assert out[2, 6 - 1] == -12 and out[2, 7 - 1] == -12


def test_type2_copies_inner_outer_lip():
    s = FapStream.empty(2)
    s.intra[0] = _intra(INTERPOLATE)
    _send(s, 0, {4: 40})  # lower_t_midlip: its outer counterpart 51 follows
    _send(s, 1, {55: -25})  # lower_t_lip_lm_o: 8 (lower_t_lip_lm, its inner counterpart) follows
    out = resolve(s)
    assert out[0, 51 - 1] == 40 and out[0, 4 - 1] == 40
    assert out[1, 8 - 1] == -25


LM_RM = ((8, 9), (10, 11), (55, 56), (57, 58))  # lower_t_lip_lm/rm, raise_b_lip_lm/rm and the outer ones


@pytest.mark.parametrize("left,right", LM_RM)
def test_type2_copies_left_right_middle_lip(left, right):
    assert PARTNERS[left - 1, 0] == right - 1 and PARTNERS[right - 1, 0] == left - 1
    s = FapStream.empty(1)
    s.intra[0] = _intra(INTERPOLATE)
    _send(s, 0, {left: -25})
    assert resolve(s)[0, right - 1] == -25


def test_type2_left_right_wins_over_inner_outer():
    s = FapStream.empty(1)
    s.intra[0] = _intra(INTERPOLATE)
    _send(s, 0, {54: 70, 6: 10})  # 53 could copy 54 (mirror) or 6 (inner): the mirror wins
    assert resolve(s)[0, 53 - 1] == 70


def test_type1_does_not_interpolate():
    s = FapStream.empty(2)
    s.intra[0] = _intra(HOLD)
    _send(s, 0, {6: 30, 4: 40})
    out = resolve(s)
    assert out[:, 7 - 1].tolist() == [0, 0] and out[:, 51 - 1].tolist() == [0, 0]


def test_type2_without_a_counterpart_holds():
    s = FapStream.empty(3)
    s.intra[0] = _intra(INTERPOLATE)
    _send(s, 0, {7: 15})
    _send(s, 1, {7: 25})
    _send(s, 2, {3: 100})  # neither 6 nor 7 sent: both hold their own last values
    out = resolve(s)
    assert out[:, 7 - 1].tolist() == [15, 25, 25]
    assert out[0, 6 - 1] == 15 and out[1, 6 - 1] == 25


def test_a_later_intra_changes_the_mask_type():
    s = FapStream.empty(2)
    s.intra[0] = _intra(HOLD)
    s.intra[1] = _intra(INTERPOLATE)
    _send(s, 0, {6: 30})
    _send(s, 1, {6: 40})
    out = resolve(s)
    assert out[:, 7 - 1].tolist() == [0, 40]


def test_interpolated_value_is_held_on_later_frames():
    s = FapStream.empty(3)
    s.intra[0] = _intra(INTERPOLATE)
    _send(s, 0, {6: 30})  # 7 shows 30 by interpolation
    # frames 1, 2: nothing sent, so 6 holds 30; the face should stay symmetric
    out = resolve(s)
    assert out[:, 6 - 1].tolist() == [30, 30, 30]
    assert out[:, 7 - 1].tolist() == [30, 30, 30]


def _viseme(stream: FapStream, frame: int, select1: int, select2: int = 0, blend: int = 63) -> None:
    stream.fap_mask[frame, 0] = True
    stream.viseme[frame] = (select1, select2, blend, 0)


def _expression(stream: FapStream, frame: int, select1: int, intensity1: int, select2: int = 0,
                intensity2: int = 0) -> None:
    stream.fap_mask[frame, 1] = True
    stream.expression[frame] = (select1, intensity1, select2, intensity2, 0, 0)


def test_high_level_expansion():
    s = FapStream.empty(4)
    _viseme(s, 0, 10, 1, 40)
    _expression(s, 0, 1, 50, 3, 20)
    _viseme(s, 2, 4)
    out = resolve(s)
    expected_0 = expand_high_level(s.viseme[:1], s.expression[:1])[0]
    assert np.array_equal(out[0, 2:], expected_0[2:])
    assert np.array_equal(out[1], out[0]), "FAP 1 and 2 hold"
    held = expand_high_level(s.viseme[2:3], s.expression[:1])[0]  # new viseme, held expression
    assert np.allclose(out[2, 2:], held[2:]) and np.array_equal(out[3], out[2])
    assert not out[:, :2].any()
    assert np.abs(out).max() > 0


def test_sent_low_level_overrides_high_level():
    s = FapStream.empty(3)
    aa = 10  # viseme 10 opens the jaw
    _viseme(s, 0, aa)
    _send(s, 1, {3: 77})
    out = resolve(s)
    profile = expand_high_level(s.viseme[:1], s.expression[:1])[0]
    assert profile[3 - 1] != 0
    assert out[0, 3 - 1] == profile[3 - 1]
    assert out[1, 3 - 1] == 77 and out[2, 3 - 1] == 77, "a sent FAP 3 wins over the viseme's FAP 3"
    others = [i for i in range(2, N_FAPS) if i != 3 - 1]
    assert np.array_equal(out[1, others], profile[others])


def test_animate_uses_the_resolved_values(procedural_face):
    s = FapStream.empty(3)
    s.intra[0] = _intra(INTERPOLATE)
    _send(s, 0, {6: 120, 3: 200})
    _viseme(s, 1, 10)
    poses = list(procedural_face.animate(s))
    values = resolve(s)
    assert len(poses) == 3
    for pose, v in zip(poses, values):
        assert np.array_equal(pose.vertices, procedural_face.deform(v).vertices)
    assert not np.array_equal(poses[0].vertices, procedural_face.mesh.vertices)


def _random_stream(seed: int, n: int = 120) -> FapStream:
    """Sparse random sends of low- and high-level FAPs, with intra headers changing mask types."""
    rng = np.random.default_rng(seed)
    s = FapStream.empty(n)
    for start in sorted({0, *rng.integers(1, n, 3).tolist()}):
        s.intra[start] = _intra({g: int(rng.choice([HOLD, INTERPOLATE])) for g in range(1, 11)})
    sent = rng.random((n, N_FAPS)) < 0.15
    s.fap_mask[:] = sent
    s.fap_values[:] = np.where(sent, rng.integers(-300, 300, (n, N_FAPS)), 0)
    vis, exp = s.fap_mask[:, 0], s.fap_mask[:, 1]
    s.viseme[vis] = np.c_[rng.integers(0, 15, (vis.sum(), 2)), rng.integers(0, 64, vis.sum()), np.zeros(vis.sum())]
    s.expression[exp] = np.c_[rng.integers(0, 7, exp.sum()), rng.integers(0, 64, exp.sum()),
                              rng.integers(0, 7, exp.sum()), rng.integers(0, 64, exp.sum()), np.zeros((exp.sum(), 2))]
    return s


@pytest.mark.parametrize("seed", range(6))
def test_resolving_frame_by_frame_equals_the_whole_stream(seed):
    """A live source is resolved one frame at a time (FrameResolver): same values as the batch."""
    from mpeg4fa.decoded import FrameResolver

    s = _random_stream(seed)
    whole = resolve(s)
    resolver = FrameResolver()
    live = np.array([resolver.push(frame) for frame in s])
    np.testing.assert_array_equal(live, whole)
    assert np.abs(whole).max() > 0


def test_resolving_in_pieces_carries_the_state():
    from mpeg4fa.decoded import ResolveState

    s = _random_stream(99, 200)
    state = ResolveState()
    pieces = [resolve(_piece(s, a, b), state)
              for a, b in ((0, 7), (7, 90), (90, 200))]
    np.testing.assert_array_equal(np.concatenate(pieces), resolve(s))


def _piece(s: FapStream, a: int, b: int) -> FapStream:
    return FapStream.from_frames([s.frame(k) for k in range(a, b)])


def test_values_no_face_can_show_are_clamped_and_said_once_per_fap():
    from mpeg4fa.face import FaceWarning

    s = FapStream.empty(6)
    s.intra[0] = _intra()
    for k, jaw in enumerate([-8, 40, -30, 0, -2, 9000]):
        _send(s, k, {3: jaw, 41: -5 if k < 2 else 0, 4: -9000 if k == 3 else 10})
    with pytest.warns(FaceWarning) as caught:
        out = resolve(s)
    said = sorted(str(w.message) for w in caught)
    assert said == [
        "FAP 3 (open_jaw) is outside 0..8192 in 4 frames of the stream (as far as 9000): clamped",
        "FAP 4 (lower_t_midlip) is outside -8192..8192 in 1 frame of the stream (as far as -9000): clamped",
        "FAP 41 (lift_l_cheek) is negative on a unidirectional FAP in 2 frames of the stream (as far as -5): "
        "clamped to 0",
    ]
    assert list(out[:, 2]) == [0, 40, 0, 0, 0, 8192]
    assert list(out[:, 40]) == [0, 0, 0, 0, 0, 0] and out[3, 3] == -8192


def test_a_live_stream_says_each_clamped_fap_once():
    import warnings

    from mpeg4fa.face import FaceWarning
    from mpeg4fa.decoded import FrameResolver

    s = FapStream.empty(5)
    s.intra[0] = _intra()
    for k in range(5):
        _send(s, k, {3: -10 - k})
    resolver = FrameResolver()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rows = [resolver.push(frame) for frame in s]
    assert [r[2] for r in rows] == [0] * 5
    messages = [str(w.message) for w in caught if issubclass(w.category, FaceWarning)]
    assert len(messages) == 1 and messages[0].startswith("FAP 3 (open_jaw) is negative")
    assert "from frame 0 on" in messages[0]
