"""Checks that the tables in spec/*.csv load, are complete and agree with each other."""
from __future__ import annotations

import numpy as np

import mpeg4fa.spec as spec

BAP_GROUP_SIZES = [3, 4, 4, 6, 6, 5, 5, 7, 7, 12, 15, 18, 18, 12, 16, 16, 13, 13, 6, 22, 22, 22, 22, 22]


def test_counts():
    assert spec.N_FAPS == len(spec.FAPS) == 68
    assert [f.number for f in spec.FAPS] == list(range(1, 69))
    assert len(spec.FAP_BY_NAME) == 68
    assert len(spec.FEATURE_POINTS) == 84
    moved = [p for p in spec.FEATURE_POINTS if p.moved_by_faps]
    assert len(moved) == 46 and len(spec.FEATURE_POINTS) - len(moved) == 38
    assert sorted(spec.FAPU) == ["AU", "ENS", "ES", "IRISD", "MNS", "MW"]
    assert len(spec.VISEMES) == 15 and spec.VISEMES[0].name == "none"
    assert len(spec.EXPRESSIONS) == 7 and spec.EXPRESSIONS[0].name == "neutral"
    assert len(spec.HIGH_LEVEL_FIELDS) == 7


def test_feature_point_group_sizes():
    sizes = [sum(p.group == g for p in spec.FEATURE_POINTS) for g in range(2, 12)]
    assert sizes == [14, 14, 6, 4, 4, 1, 10, 15, 10, 6]


def test_fap_spot_values():
    jaw = spec.FAP_BY_NAME["open_jaw"]
    assert jaw is spec.FAPS[2]
    assert (jaw.fapu, jaw.direction, jaw.group, jaw.feature_point) == ("MNS", "down", 2, ("2.1",))
    assert (jaw.quant_step, jaw.i_max, jaw.p_max) == (4, 1080, 360)
    pitch = spec.FAPS[47]
    assert (pitch.name, pitch.fapu, pitch.quant_step) == ("head_pitch", "AU", 170)
    assert spec.FAPS[62].i_max == 680
    assert spec.FAPS[46].feature_point == ("6.3", "6.4")
    uni = [f.number for f in spec.FAPS if f.unidirectional]
    assert uni == [3, 14, 41, 42, 47]


def test_high_level_faps_have_no_low_level_fields():
    for fap in spec.FAPS[:2]:
        assert fap.fapu is None and fap.direction is None and fap.unidirectional is None
        assert fap.feature_point == () and fap.i_max is None and fap.p_max is None
    for fap in spec.FAPS[2:]:
        assert fap.fapu in spec.FAPU and fap.unidirectional is not None
        assert fap.i_max > 0 and fap.p_max > 0


def test_arrays():
    for arr in (spec.QUANT_STEP, spec.I_MAX_DEFAULT, spec.P_MAX_DEFAULT, spec.FAP_GROUP):
        assert arr.shape == (68,) and arr.dtype == np.int32
        assert not arr.flags.writeable
    assert spec.QUANT_STEP[2] == 4 and spec.I_MAX_DEFAULT[2] == 1080 and spec.P_MAX_DEFAULT[2] == 360
    assert spec.I_MAX_DEFAULT[0] == spec.I_MAX_DEFAULT[1] == 0
    assert spec.P_MAX_DEFAULT[0] == spec.P_MAX_DEFAULT[1] == 0


def test_high_level_fields():
    fields = [(f.fap, f.field) for f in spec.HIGH_LEVEL_FIELDS]
    assert fields == [(1, "select1"), (1, "select2"), (1, "blend"),
                      (2, "select1"), (2, "intensity1"), (2, "select2"), (2, "intensity2")]
    for f in spec.HIGH_LEVEL_FIELDS:
        assert f.i_min == 0 and f.p_min == -f.i_max and f.p_max == f.i_max
        assert f.quantised == (f.i_max == 63)
    assert {f.i_max for f in spec.HIGH_LEVEL_FIELDS if "select" in f.field and f.fap == 1} == {
        len(spec.VISEMES) - 1}
    assert {f.i_max for f in spec.HIGH_LEVEL_FIELDS if "select" in f.field and f.fap == 2} == {
        len(spec.EXPRESSIONS) - 1}


def test_group_slices_tile_all_columns():
    slices = spec.FAP_GROUP_SLICES
    assert len(slices) == 10
    assert slices[0] == (0, 2) and slices[1] == (2, 18)
    assert slices[0][0] == 0 and slices[-1][1] == 68
    for (_, stop), (start, _) in zip(slices, slices[1:]):
        assert stop == start
    for group, (start, stop) in enumerate(slices, 1):
        assert start < stop
        assert (spec.FAP_GROUP[start:stop] == group).all()


def test_fapu_points_exist():
    labels = {p.label for p in spec.FEATURE_POINTS}
    for fapu in spec.FAPU.values():
        if fapu.symbol == "AU":
            assert fapu.point_a is None and fapu.divisor is None and fapu.radians == 1e-5
        else:
            assert {fapu.point_a, fapu.point_b} <= labels
            assert fapu.axis in ("x", "y") and fapu.divisor == 1024
            role = fapu.symbol + "0"
            assert role in next(p for p in spec.FEATURE_POINTS if p.label == fapu.point_a).fapu_role
            assert role in next(p for p in spec.FEATURE_POINTS if p.label == fapu.point_b).fapu_role


def test_fap_feature_points_exist():
    labels = {p.label for p in spec.FEATURE_POINTS}
    for fap in spec.FAPS[2:]:
        assert fap.feature_point and set(fap.feature_point) <= labels, fap.name


def test_moved_by_faps_matches_fap_table():
    by_point: dict[str, list[int]] = {}
    for fap in spec.FAPS:
        for label in fap.feature_point:
            by_point.setdefault(label, []).append(fap.number)
    for point in spec.FEATURE_POINTS:
        assert list(point.moved_by_faps) == by_point.get(point.label, []), point.label


def test_bap_groups():
    assert [len(g) for g in spec.BAP_GROUPS] == BAP_GROUP_SIZES
    flat = [b for g in spec.BAP_GROUPS for b in g]
    assert sorted(flat) == list(range(spec.N_BAPS))
    assert spec.BAP_GROUPS[0] == (0, 1, 2)
    assert spec.BAP_GROUPS[1] == (3, 5, 9, 13)
    assert spec.BAP_GROUPS[19] == tuple(range(186, 208))
    assert sum(BAP_GROUP_SIZES[:19]) == 186


def test_bap_quant_tables():
    for arr in (spec.BAP_QUANT_STEP, spec.BAP_QUANT_STEP_ALT):
        assert arr.shape == (296,) and arr.dtype == np.int32
        assert (arr[186:] == 1).all()
    assert list(spec.BAP_QUANT_STEP[180:186]) == [2, 2, 2, 170, 170, 170]
    assert set(spec.BAP_QUANT_STEP[:186].tolist()) == {2, 170, 256, 512}
    assert set(spec.BAP_QUANT_STEP_ALT[:186].tolist()) == {64, 128, 256, 512}
    assert spec.BAP_PRED_SCALE.shape == (32,) and spec.BAP_PRED_SCALE.dtype == np.int32
    assert spec.BAP_PRED_SCALE[0] == 0 and spec.BAP_PRED_SCALE[31] == 127
    assert (np.diff(spec.BAP_PRED_SCALE) > 0).all()


def test_checkout_fallback_finds_spec_folder():
    from mpeg4fa.spec import _load

    assert (_load.data_dir() / "faps.csv").is_file()


def test_tables_come_from_the_spec_folder():
    """Installed or not, the loader reads the top-level spec/ files (shipped as mpeg4fa.spec_data)."""
    from pathlib import Path

    from mpeg4fa.spec import _load

    checkout = Path(__file__).resolve().parents[2] / "spec"
    for csv_file in sorted(checkout.glob("*.csv")):
        assert (_load.data_dir() / csv_file.name).read_text() == csv_file.read_text()
