"""The suite's reference model: hand-made frames with known answers, and agreement with the project's
decoder (``mpeg4fa.decoded``) and face engine FAPU (``mpeg4fa.face.fapu``), which it must not import."""
from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance import reference as ref
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.reference import (
    TOLERANCE, feature_point_positions, feature_point_tolerance, fapu_from_points, fapu_units, rotations,
    shown_values,
)
from mpeg4fa.spec import (
    ANGLE_UNIT, EXPRESSION_PROFILES, FAP_BY_NAME, FAPS, FAPU_NAMES, N_FAP_GROUPS, N_FAPS, VISEME_PROFILES, VISEMES,
    EXPRESSIONS,
)

HOLD, INTERP = 1, 2
COL = {name: record.number - 1 for name, record in FAP_BY_NAME.items()}


def frames(n: int, types: int | list[int] = HOLD):
    """Empty arrays for n frames, every group governed by ``types``."""
    t = np.broadcast_to(np.asarray(types), (N_FAP_GROUPS,))
    return (np.zeros((n, N_FAPS), bool), np.zeros((n, N_FAPS), np.int64), np.zeros((n, 4), np.int64),
            np.zeros((n, 6), np.int64), np.tile(t, (n, 1)))


def send(arrays, k: int, fap: int, value: int) -> None:
    mask, values = arrays[0], arrays[1]
    mask[k, fap - 1], values[k, fap - 1] = True, value


# ---- shown values: hold and interpolate ---------------------------------------------------------
def test_hold_keeps_the_last_value_sent_and_zero_before():
    a = frames(4)
    send(a, 1, 3, 200)
    send(a, 3, 3, 50)
    out = shown_values(*a)
    assert out[:, 2].tolist() == [0, 200, 200, 50]
    assert not out[:, :2].any() and not out[:, 3:].any()


def test_interpolate_copies_left_right_counterpart_sent_in_the_same_frame():
    a = frames(2, INTERP)
    send(a, 0, 19, 300)          # close_t_l_eyelid; close_t_r_eyelid (20) not sent
    out = shown_values(*a)
    assert out[0, 19] == 300 and out[1, 19] == 300     # copied, then held like a sent value
    b = frames(1, HOLD)
    send(b, 0, 19, 300)
    assert shown_values(*b)[0, 19] == 0                 # mask type 1: no copy


def test_interpolate_inner_outer_when_no_left_right_partner_is_sent():
    a = frames(1, INTERP)
    send(a, 0, 4, -120)          # lower_t_midlip (no left/right partner) -> 51 lower_t_midlip_o
    send(a, 0, 59, 77)           # raise_l_cornerlip_o: 60 (its l/r partner) and 12 (inner) unsent
    out = shown_values(*a)
    assert out[0, 50] == -120    # 51 <- 4
    assert out[0, 59] == 77      # 60 <- 59 (left/right wins)
    assert out[0, 11] == 77      # 12 <- 59 (inner <- outer)
    assert out[0, 12] == 0       # 13: partners 12 and 60 are not *sent*, so it holds 0


def test_left_right_wins_over_inner_outer():
    a = frames(1, INTERP)
    send(a, 0, 7, 40)            # stretch_r_cornerlip: l/r partner of 6
    send(a, 0, 53, 90)           # stretch_l_cornerlip_o: i/o partner of 6
    assert shown_values(*a)[0, 5] == 40


def test_interpolation_follows_the_group_type_of_the_unsent_fap():
    types = [HOLD] * N_FAP_GROUPS
    types[7] = INTERP            # group 8 (outer lip) interpolates, group 2 (inner lip) holds
    a = frames(1, types)
    send(a, 0, 4, 10)
    send(a, 0, 52, 20)
    out = shown_values(*a)
    assert out[0, 50] == 10      # 51 <- 4
    assert out[0, 4] == 0        # 5 does not copy 52: its group holds


def test_interpolated_then_unsent_holds_the_copy_and_a_sent_value_replaces_it():
    a = frames(3, INTERP)
    send(a, 0, 19, 100)
    send(a, 2, 20, -5)
    out = shown_values(*a)
    assert out[:, 19].tolist() == [100, 100, -5]
    assert out[:, 18].tolist() == [100, 100, -5]     # unsent again: copies its partner sent now


# ---- shown values: FAP 1 and FAP 2 ------------------------------------------------------------
def _viseme(name: str) -> np.ndarray:
    return np.asarray(VISEME_PROFILES["mpeg4"][name], dtype=np.float64)


def _expression(name: str) -> np.ndarray:
    return np.asarray(EXPRESSION_PROFILES[name], dtype=np.float64)


@pytest.mark.parametrize("blend", [0, 31, 63])
def test_viseme_blend(blend):
    a = frames(1)
    a[0][0, 0] = True
    a[2][0] = [10, 1, blend, 0]  # AA with PP
    got = shown_values(*a)[0]
    want = _viseme(VISEMES[10].name) * blend / 63 + _viseme(VISEMES[1].name) * (1 - blend / 63)
    want[:2] = 0
    assert np.allclose(got, want, atol=1e-12, rtol=0)
    if blend == 63:
        assert np.allclose(got[2:], _viseme(VISEMES[10].name)[2:])
    if blend == 0:
        assert np.allclose(got[2:], _viseme(VISEMES[1].name)[2:])


def test_blend_above_63_counts_as_63():
    a = frames(1)
    a[0][0, 0] = True
    a[2][0] = [10, 1, 65, 0]
    assert np.allclose(shown_values(*a)[0, 2:], _viseme(VISEMES[10].name)[2:])


def test_two_expressions_add_with_their_own_intensities():
    a = frames(2)
    a[0][0, 1] = True
    a[3][0] = [1, 40, 6, 21, 0, 0]   # joy 40, surprise 21: need not add up to 63
    out = shown_values(*a)
    want = _expression(EXPRESSIONS[1].name) * 40 / 63 + _expression(EXPRESSIONS[6].name) * 21 / 63
    assert np.allclose(out[0, 2:], want[2:]) and np.allclose(out[1], out[0])   # held in frame 1
    assert np.abs(want[2:]).max() > 0


def test_sent_low_level_fap_overrides_the_high_level_value():
    jaw = COL["open_jaw"]
    name = next(n for n, p in VISEME_PROFILES["mpeg4"].items() if p[jaw] != 0)
    select = next(v.number for v in VISEMES if v.name == name)
    a = frames(3)
    a[0][:, 0] = True
    a[2][:] = [select, select, 63, 0]
    send(a, 1, 3, 7)
    out = shown_values(*a)
    assert out[0, jaw] == _viseme(name)[jaw]
    assert out[1, jaw] == 7 and out[2, jaw] == 7       # sent once, then held: still overrides
    others = [c for c in range(2, N_FAPS) if c != jaw]
    assert np.allclose(out[1, others], _viseme(name)[others])


def test_bad_select_and_shapes_are_refused():
    a = frames(1)
    a[0][0, 0] = True
    a[2][0] = [15, 0, 0, 0]
    with pytest.raises(ConformanceError):
        shown_values(*a)
    with pytest.raises(ConformanceError):
        shown_values(np.zeros((2, 68), bool), np.zeros((2, 67)), np.zeros((2, 4)), np.zeros((2, 6)),
                     np.zeros((2, 10)))


# ---- FAPU -------------------------------------------------------------------------------------
def symmetric_face() -> dict[str, np.ndarray]:
    """A hand-made neutral face: IRISD0 = 10, ES0 = 60, ENS0 = 40, MNS0 = 20, MW0 = 50 (x to the left)."""
    p = {
        "3.1": (30, 5, 10), "3.3": (30, -5, 10), "3.2": (-30, 5, 10), "3.4": (-30, -5, 10),
        "3.5": (30, 0, 12), "3.6": (-30, 0, 12), "9.15": (0, -40, 20), "2.2": (0, -60, 18),
        "8.3": (25, -62, 16), "8.4": (-25, -62, 16), "2.1": (0, -100, 10), "7.1": (0, -80, -60),
    }
    return {k: np.array(v, dtype=np.float64) for k, v in p.items()}


def test_fapu_on_a_hand_made_symmetric_face():
    units = fapu_from_points(symmetric_face())
    assert tuple(units) == FAPU_NAMES
    assert units == {"IRISD0": 10 / 1024, "ES0": 60 / 1024, "ENS0": 40 / 1024, "MNS0": 20 / 1024,
                     "MW0": 50 / 1024}
    per_fap = fapu_units(units)
    assert per_fap[0] == per_fap[1] == 0
    assert per_fap[COL["open_jaw"]] == 20 / 1024            # MNS
    assert per_fap[COL["close_t_l_eyelid"]] == 10 / 1024    # IRISD, not MNS
    assert per_fap[COL["head_yaw"]] == ANGLE_UNIT == 1e-5
    assert per_fap[COL["stretch_l_cornerlip"]] == 50 / 1024
    assert np.isfinite(per_fap).all()


def test_subset_face_measures_what_it_can():
    face = symmetric_face()
    del face["3.1"], face["8.4"]
    units = fapu_from_points(face)
    assert "MW0" not in units
    assert units["IRISD0"] == 10 / 1024      # from the right eye
    assert np.isnan(fapu_units(units)[COL["shift_jaw"]])


def test_mirrored_face_is_refused():
    face = {k: v * np.array([-1, 1, 1]) for k, v in symmetric_face().items()}
    with pytest.raises(ConformanceError):
        fapu_from_points(face)


def test_fapu_agrees_with_the_face_engine(procedural_face):
    from mpeg4fa.face.fapu import measure_fapu

    points = procedural_face.feature_points()
    engine = measure_fapu(points).as_dict()
    ours = fapu_from_points(points)
    assert set(ours) == set(engine)
    for name in FAPU_NAMES:
        assert ours[name] == pytest.approx(engine[name] / 1024, rel=1e-12), name


# ---- feature points ---------------------------------------------------------------------------
def test_open_jaw_moves_2_1_down_by_value_times_mns():
    face = symmetric_face()
    a = frames(2)
    send(a, 1, 3, 512)
    pos = feature_point_positions(face, shown_values(*a))
    assert np.allclose(pos["2.1"][0], face["2.1"])
    assert np.allclose(pos["2.1"][1], face["2.1"] + [0, -512 * 20 / 1024, 0])    # 10 units down
    assert np.allclose(pos["2.2"], face["2.2"])


def test_close_t_l_eyelid_uses_irisd():
    face = symmetric_face()
    a = frames(1)
    send(a, 0, 19, 1024)
    pos = feature_point_positions(face, shown_values(*a))
    assert np.allclose(pos["3.1"][0], face["3.1"] + [0, -10, 0])     # a full IRISD0 down: lid shut
    assert np.allclose(pos["3.2"][0], face["3.2"])


def test_faps_on_one_point_add_and_directions_follow_the_axes():
    face = symmetric_face()
    a = frames(1)
    send(a, 0, 14, 1024)     # thrust_jaw: forward (+z), MNS
    send(a, 0, 15, 1024)     # shift_jaw: toward the face's right (-x), MW
    send(a, 0, 3, 1024)      # open_jaw: down
    pos = feature_point_positions(face, shown_values(*a))
    assert np.allclose(pos["2.1"][0], face["2.1"] + [-50, -20, 20])


def test_missing_points_and_unmeasurable_fapu_are_left_out():
    face = symmetric_face()
    del face["8.4"]          # no MW
    a = frames(1)
    send(a, 0, 15, 1024)     # shift_jaw (MW): skipped
    send(a, 0, 3, 1024)
    send(a, 0, 27, 100)      # thrust_l_eyeball moves 3.5 (present); pupil dilation moves nothing
    send(a, 0, 29, 100)
    pos = feature_point_positions(face, shown_values(*a))
    assert np.allclose(pos["2.1"][0], face["2.1"] + [0, -20, 0])
    assert "8.4" not in pos and "4.1" not in pos
    assert np.allclose(pos["3.5"][0], face["3.5"] + [0, 0, 100 * 60 / 1024])


def test_rotations_are_in_radians_and_eyeballs_move_no_point():
    face = symmetric_face()
    a = frames(1)
    send(a, 0, 23, -5000)    # yaw_l_eyeball: no centre given (rule 18)
    send(a, 0, 47, 3000)     # tongue_roll (rule 20)
    shown = shown_values(*a)
    rot = rotations(shown)
    assert set(rot) == {f.number for f in FAPS if f.fapu == "AU"}
    assert rot[23][0] == pytest.approx(-0.05)
    pos = feature_point_positions(face, shown)
    assert all(np.allclose(pos[k][0], face[k]) for k in pos)
    assert not any(p.any() for p in ref.checkable(face, shown).values())


@pytest.mark.parametrize("fap, probe, toward", [
    (48, (0, -80, 40), (0, -1, 0)),    # head_pitch "down": a point in front of 7.1 goes down
    (49, (0, -80, 40), (1, 0, 0)),     # head_yaw "left": it goes to the face's left (+x)
    (50, (0, 20, -60), (-1, 0, 0)),    # head_roll "right": a point above 7.1 goes to the face's right
])
def test_a_head_rotation_turns_every_point_about_7_1(fap, probe, toward):
    face = symmetric_face()
    face["probe"] = np.array(probe, dtype=np.float64)
    a = frames(2)
    send(a, 1, fap, 100000)  # one radian
    shown = shown_values(*a)
    pos = feature_point_positions(face, shown)
    centre = face["7.1"]
    assert set(pos) == set(face)                       # under a head rotation every point is driven
    assert np.allclose(pos["7.1"][1], centre)
    for label, start in face.items():
        assert np.allclose(pos[label][0], start)
        assert np.linalg.norm(pos[label][1] - centre) == pytest.approx(np.linalg.norm(start - centre))
    offset = face["probe"] - centre
    moved = pos["probe"][1] - centre
    assert np.dot(moved - offset, toward) > 0.5 * np.linalg.norm(offset)
    assert np.degrees(np.arccos(np.dot(moved, offset) / np.dot(offset, offset))) == pytest.approx(np.degrees(1.0))
    pin = ref.checkable(face, shown)
    assert all(pin[k][1].all() and not pin[k][0].any() for k in pin)


def test_head_rotations_combine_roll_then_pitch_then_yaw_and_pin_nothing():
    face = symmetric_face()
    a = frames(2)
    send(a, 0, 48, 20000)
    send(a, 0, 49, 30000)
    send(a, 0, 50, 10000)
    send(a, 1, 49, 30000)
    send(a, 1, 3, 512)       # a jaw drop turned with the head: in the head's frame first
    shown = shown_values(*a)
    pos = feature_point_positions(face, shown)
    c = face["7.1"]
    turn = ref.head_orientation({48: 0.2, 49: 0.3, 50: 0.1})
    yaw, pitch, roll = (ref.head_orientation({n: x}) for n, x in ((49, 0.3), (48, 0.2), (50, 0.1)))
    assert np.allclose(turn, yaw @ pitch @ roll)
    assert np.allclose(pos["2.2"][0], c + turn @ (face["2.2"] - c))
    assert np.allclose(pos["2.1"][1], c + turn @ (face["2.1"] + [0, -10, 0] - c))  # 48, 50 held (rule 2)
    assert not any(p.any() for p in ref.checkable(face, shown).values())
    assert ref.RULES[22][1] == "M"


def test_tolerances():
    assert set(TOLERANCE) == {"shown", "feature_points"}
    face = symmetric_face()
    tol = feature_point_tolerance(face)
    smallest_unit = min(fapu_from_points(face).values())
    assert 0 < tol < smallest_unit / 10      # a one-FAPU error is always caught


def test_reference_does_not_use_the_decoder_or_face_engine():
    for name in ("reference.py", "reference_fapu.py"):
        tree = ast.parse(Path(ref.__file__).with_name(name).read_text())
        mods = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        mods |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        assert not any(m and (m.startswith("mpeg4fa.face") or m.startswith("mpeg4fa.decoded")) for m in mods)


# ---- agreement with the project's decoder ------------------------------------------------------
def random_stream(seed: int, n: int):
    from mpeg4fa.fba import FapStream

    rng = np.random.default_rng(seed)
    s = FapStream.empty(n)
    dens = rng.choice([0.2, 0.5, 0.9])
    s.fap_mask[:] = rng.random((n, N_FAPS)) < dens
    for k, record in enumerate(FAPS[2:], start=2):
        big = 900 if record.fapu == "AU" else 300   # P differences stay inside 31*60 at fap_quant 0
        lo = 0 if record.unidirectional else -big
        s.fap_values[:, k] = rng.integers(lo, big + 1, n)
    s.fap_values[~s.fap_mask] = 0
    s.viseme[:] = np.column_stack([rng.integers(0, len(VISEMES), (n, 2)), rng.integers(0, 64, n),
                                   np.zeros(n, int)])
    s.expression[:] = np.column_stack([rng.integers(0, len(EXPRESSIONS), n), rng.integers(0, 64, n),
                                       rng.integers(0, len(EXPRESSIONS), n), rng.integers(0, 64, n),
                                       np.zeros((n, 2), int)])
    s.viseme[~s.fap_mask[:, 0]] = 0
    s.expression[~s.fap_mask[:, 1]] = 0
    s.timestamps[:] = np.arange(n) / 25.0
    return s, rng


def test_agrees_with_the_project_decoder_on_random_streams():
    """decode(encode(random stream)) through both models; every rule's branch is met along the way."""
    from mpeg4fa.decoded import resolve
    from mpeg4fa.fba import EncodeOptions, decode, encode

    met = {"interpolated": 0, "overridden": 0, "expanded": 0, "held": 0}
    for seed in range(16):
        s, rng = random_stream(seed, int(6 + seed % 4 * 8))
        types = [int(t) for t in rng.choice([1, 2], N_FAP_GROUPS)]
        options = EncodeOptions(fap_quant=int(rng.choice([0, 1, 2, 5])), intra_period=int(rng.choice([0, 4])),
                                mask_types=types, fps=25.0)
        d = decode(encode(s, options))
        group_types = d.group_mask_types()
        ours = shown_values(d.fap_mask, d.fap_values, d.viseme, d.expression, group_types)
        theirs = resolve(d)
        bad = np.argwhere(np.abs(ours - theirs) > 1e-9)
        assert not len(bad), f"seed {seed}: first disagreements (frame, column): {bad[:5].tolist()}"
        held_only = shown_values(d.fap_mask, d.fap_values, d.viseme, d.expression, np.ones_like(group_types))
        no_high = shown_values(d.fap_mask, d.fap_values, np.zeros_like(d.viseme), np.zeros_like(d.expression),
                               group_types)
        unsent = ~d.fap_mask.astype(bool)
        unsent[:, :2] = False
        met["interpolated"] += int((ours != held_only).sum())
        met["expanded"] += int(((ours != no_high) & unsent).sum())
        high_mask = d.fap_mask.astype(bool).copy()
        high_mask[:, 2:] = False
        high_only = shown_values(high_mask, d.fap_values, d.viseme, d.expression, group_types)
        met["overridden"] += int(((ours == no_high) & (high_only != no_high)).sum())
        met["held"] += int((unsent & (ours != 0)).sum())
    assert all(v > 0 for v in met.values()), met


def test_rules_table_in_the_docstring_matches_the_data():
    import re

    rows = re.findall(r"^(\d+)\s{2,}.*?\s([VSM])\s{2,}", ref.__doc__, flags=re.M)
    assert {int(n): c for n, c in rows} == {n: c for n, (_, c) in ref.RULES.items()}
    assert ref.weakest([1, 5]) == "S" and ref.weakest([1, 3]) == "M" and ref.weakest([]) == "V"


def test_checkable_pins_only_the_driven_axis_of_a_lone_fap():
    face = symmetric_face()
    a = frames(4)
    send(a, 0, 3, 100)                        # open_jaw alone: 2.1's y
    send(a, 1, 3, 100)
    send(a, 1, 14, 100)                       # with thrust_jaw: two axes on 2.1, nothing pinned
    send(a, 2, 49, 1000)                      # a rotation: nothing pinned
    pin = ref.checkable(face, shown_values(*a))
    assert pin["2.1"][0].tolist() == [False, True, False]
    assert not pin["2.1"][1].any() and not pin["2.1"][2].any() and not pin["2.1"][3].any()
    assert not any(pin[k][0].any() for k in pin if k != "2.1")


def test_checkable_components_agree_with_the_face_engine(procedural_face):
    from mpeg4fa.spec import FEATURE_POINTS

    neutral = procedural_face.feature_points()
    tol = feature_point_tolerance(neutral)
    labels = [f.label for f in FEATURE_POINTS]
    checked = 0
    for number in (3, 4, 6, 19, 21, 27, 31, 39, 44, 53, 61, 65, 48, 49, 50):
        values = np.zeros((1, N_FAPS))
        values[0, number - 1] = 15000 if number in (48, 49, 50) else 300
        got = dict(zip(labels, procedural_face.pose_values(values[0]).feature_points))
        want, pin = feature_point_positions(neutral, values), ref.checkable(neutral, values)
        for label, rows in pin.items():
            for c in np.flatnonzero(rows[0]):
                checked += 1
                assert abs(got[label][c] - want[label][0, c]) <= tol, (number, label, "xyz"[c])
    assert checked >= 12 + 3 * 3 * 84
