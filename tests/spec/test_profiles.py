"""Checks of the viseme and expression profiles (spec/*_faps.csv, chinese_visemes.csv) and their blends."""
from __future__ import annotations

import numpy as np
import pytest

import mpeg4fa.spec as spec
from mpeg4fa.errors import MpegFaError
from mpeg4fa.spec import _load, profiles
from mpeg4fa.spec.profiles import (
    CHINESE_VISEME_BY_PINYIN, CHINESE_VISEMES, EXPRESSION_PROFILES, VISEME_PROFILES,
    SpecError, build_expression_profiles, build_viseme_profiles, expand_high_level, expression_blend,
    high_level_problem, viseme_blend,
)

ZH_NAMES = ["a", "bpm", "dtnl", "e", "f", "gkh", "i", "jqx", "o", "r", "uv", "zcs", "zhchsh", "n", "ng"]
INITIALS = "b p m f d t n l g k h j q x zh ch sh r z c s y w".split()
# Finals in pypinyin's strict spelling (ü written v; iu, ui, un restored to iou, uei, uen).
FINALS = ("a o e ê er ai ei ao ou an en ang eng ong i u v ia ie iao iou ian in iang ing iong io "
          "ua uo uai uei uan uen uang ueng ve van vn").split()
MIRROR = [(6, 7), (8, 9), (10, 11), (12, 13), (53, 54), (55, 56), (57, 58), (59, 60), (39, 40), (41, 42),
          (31, 32), (33, 34), (35, 36), (37, 38), (19, 20), (21, 22), (61, 62)]


def fap(profile: np.ndarray, number: int) -> int:
    return int(profile[number - 1])


def all_profiles():
    for set_name, table in VISEME_PROFILES.items():
        for name, profile in table.items():
            yield f"{set_name}/{name}", profile
    for name, profile in EXPRESSION_PROFILES.items():
        yield f"expression/{name}", profile


# ---- loading and validation ------------------------------------------------------------------------

def test_headers():
    for name, header in (("viseme_faps.csv", "set,viseme,fap,value"),
                         ("expression_faps.csv", "expression,fap,value"),
                         ("chinese_visemes.csv", "viseme,class,pinyin,description")):
        assert _load.read_table(name, header)
        with pytest.raises(ValueError, match="header"):
            _load.read_table(name, header.replace(",", ";", 1))


def test_viseme_sets_and_names():
    assert list(VISEME_PROFILES) == ["mpeg4", "zh"]
    assert list(VISEME_PROFILES["mpeg4"]) == [v.name for v in spec.VISEMES]
    assert [v.name for v in CHINESE_VISEMES] == ZH_NAMES
    assert list(VISEME_PROFILES["zh"]) == ["none"] + ZH_NAMES
    for set_name in VISEME_PROFILES:
        assert not VISEME_PROFILES[set_name]["none"].any()
    assert list(EXPRESSION_PROFILES) == [e.name for e in spec.EXPRESSIONS]
    assert not EXPRESSION_PROFILES["neutral"].any()


def test_profile_arrays():
    for label, profile in all_profiles():
        assert profile.shape == (68,) and profile.dtype == np.int32, label
        assert not profile.flags.writeable, label
        assert profile[0] == profile[1] == 0, label
        for f in spec.FAPS:
            if f.unidirectional:
                assert profile[f.number - 1] >= 0, (label, f.name)


def test_values_are_plausible_and_codable():
    """Every value fits the default intra range at fap_quant 1, so an encoder can send it as is."""
    limit = spec.I_MAX_DEFAULT * spec.QUANT_STEP
    for label, profile in all_profiles():
        assert np.all(np.abs(profile) <= limit), label
        assert np.abs(profile).max() <= 1000, label


def test_every_profile_is_mirror_symmetric():
    for label, profile in all_profiles():
        for left, right in MIRROR:
            assert fap(profile, left) == fap(profile, right), (label, left, right)


NAMES = {"mpeg4": ("none", "PP", "AA"), "zh": ("none", "a")}


def visemes(*rows: str) -> list[dict[str, str]]:
    return [dict(zip(("set", "viseme", "fap", "value"), r.split(","))) for r in rows]


def test_viseme_validator_accepts_good_rows():
    got = build_viseme_profiles(visemes("mpeg4,PP,4,60", "mpeg4,AA,3,800", "zh,a,3,900"), NAMES)
    assert fap(got["mpeg4"]["PP"], 4) == 60 and fap(got["zh"]["a"], 3) == 900
    assert not got["mpeg4"]["none"].any()


@pytest.mark.parametrize("bad, message", [
    ("xx,PP,4,60", "unknown viseme set"),
    ("mpeg4,pp,4,60", "not a viseme of set"),
    ("zh,PP,4,60", "not a viseme of set"),
    ("mpeg4,none,4,60", "rest pose"),
    ("mpeg4,PP,1,60", "not a low-level FAP"),
    ("mpeg4,PP,69,60", "not a low-level FAP"),
    ("mpeg4,PP,4,6.5", "not an integer"),
    ("mpeg4,PP,x,6", "not an integer"),
    ("mpeg4,PP,3,-10", "unidirectional"),
    ("mpeg4,AA,3,800", "given twice"),
])
def test_viseme_validator_rejects(bad, message):
    rows = visemes("mpeg4,PP,4,60", "mpeg4,AA,3,800", "zh,a,3,900", bad)
    with pytest.raises(ValueError, match=message) as err:
        build_viseme_profiles(rows, NAMES)
    assert "line 5" in str(err.value)


def test_viseme_validator_wants_every_viseme():
    with pytest.raises(ValueError, match="mpeg4/AA has no rows"):
        build_viseme_profiles(visemes("mpeg4,PP,4,60", "zh,a,3,900"), NAMES)


STANDARD = ("neutral", "joy", "anger")


def expressions(*rows: str) -> list[dict[str, str]]:
    return [dict(zip(("expression", "fap", "value"), r.split(","))) for r in rows]


def test_expression_validator_keeps_extra_names():
    got = build_expression_profiles(expressions("smirk,59,120", "joy,59,200", "anger,31,-150"), STANDARD)
    assert list(got) == ["neutral", "joy", "anger", "smirk"]
    assert fap(got["smirk"], 59) == 120 and not got["neutral"].any()


@pytest.mark.parametrize("bad, message", [
    ("neutral,3,10", "zero face"),
    ("Joy,59,200", "bad expression name"),
    ("joy,2,10", "not a low-level FAP"),
    ("joy,41,-5", "unidirectional"),
    ("joy,59,100", "given twice"),
    ("joy,59,1e3", "not an integer"),
])
def test_expression_validator_rejects(bad, message):
    with pytest.raises(ValueError, match=message):
        build_expression_profiles(expressions("joy,59,200", "anger,31,-150", bad), STANDARD)
    with pytest.raises(ValueError, match="anger has no rows"):
        build_expression_profiles(expressions("joy,59,200"), STANDARD)


# ---- what the profiles look like ---------------------------------------------------------------------

@pytest.mark.parametrize("set_name, name", [("mpeg4", "PP"), ("zh", "bpm")])
def test_bilabials_close_the_lips(set_name, name):
    p = VISEME_PROFILES[set_name][name]
    assert fap(p, 3) <= 100                                   # jaw nearly closed
    assert fap(p, 4) > 0 and fap(p, 5) > 0
    assert fap(p, 4) + fap(p, 5) >= fap(p, 3)                 # inner lips meet or press
    assert fap(p, 51) + fap(p, 52) >= fap(p, 3)               # and the outer ones


@pytest.mark.parametrize("set_name, name", [("mpeg4", "AA"), ("zh", "a")])
def test_open_vowels_open_the_jaw(set_name, name):
    p = VISEME_PROFILES[set_name][name]
    assert 700 <= fap(p, 3) <= 1000
    assert fap(p, 3) - fap(p, 4) - fap(p, 5) > fap(p, 3)      # lips part further than the jaw


@pytest.mark.parametrize("set_name, name", [("mpeg4", "ou"), ("mpeg4", "oh"), ("zh", "uv"), ("zh", "o"),
                                            ("zh", "zhchsh"), ("mpeg4", "CH")])
def test_rounded_visemes(set_name, name):
    p = VISEME_PROFILES[set_name][name]
    assert fap(p, 53) < 0 and fap(p, 6) < 0                   # corners drawn in
    assert fap(p, 16) > 0 and fap(p, 17) > 0                  # lips pushed forward


def test_rounding_degrees():
    zh = VISEME_PROFILES["zh"]
    assert fap(zh["uv"], 53) < fap(zh["o"], 53) < fap(zh["r"], 53) < 0
    assert fap(zh["uv"], 3) < fap(zh["o"], 3)


@pytest.mark.parametrize("set_name, name", [("mpeg4", "ih"), ("mpeg4", "E"), ("mpeg4", "SS"),
                                            ("zh", "i"), ("zh", "jqx"), ("zh", "zcs")])
def test_spread_visemes(set_name, name):
    p = VISEME_PROFILES[set_name][name]
    assert fap(p, 6) > 0 and fap(p, 53) > 0


@pytest.mark.parametrize("set_name, name", [("mpeg4", "FF"), ("zh", "f")])
def test_labiodental_tucks_the_lower_lip(set_name, name):
    p = VISEME_PROFILES[set_name][name]
    # the lower lip drawn back under the upper incisors, the upper lip up off them (the contact itself
    # is measured on the face: tests/render/test_mouth_contact.py)
    assert fap(p, 16) <= -200 and fap(p, 52) > 0 and fap(p, 4) < 0


def test_tongue_visemes():
    m, zh = VISEME_PROFILES["mpeg4"], VISEME_PROFILES["zh"]
    assert fap(m["TH"], 45) > 0 and 0 < fap(m["TH"], 3) <= 200
    for p in (m["DD"], m["nn"], zh["dtnl"], zh["n"]):
        assert fap(p, 44) >= 400
    for p in (m["kk"], zh["gkh"], zh["ng"]):
        assert fap(p, 46) >= 400 and fap(p, 44) <= 0
    assert fap(zh["ng"], 3) > fap(zh["n"], 3) > 0


def test_expression_directions():
    e = EXPRESSION_PROFILES
    joy = e["joy"]
    assert fap(joy, 59) > 0 and fap(joy, 53) > 0 and fap(joy, 12) > 0 and fap(joy, 41) > 0
    assert all(fap(joy, k) == 0 for k in range(31, 37))
    sad = e["sadness"]
    assert fap(sad, 31) > 0 and fap(sad, 35) < 0 and 0 < fap(sad, 19) < 300
    assert fap(sad, 59) < 0 and fap(sad, 12) < 0
    anger = e["anger"]
    assert fap(anger, 31) < 0 and fap(anger, 37) > 0 and fap(anger, 19) < 0
    assert fap(anger, 4) > 0 and fap(anger, 5) > 0
    fear = e["fear"]
    assert all(fap(fear, k) > 0 for k in range(31, 39))
    assert fap(fear, 31) > fap(fear, 35) and fap(fear, 19) < 0
    disgust = e["disgust"]
    assert fap(disgust, 51) < 0 and fap(disgust, 4) < 0 and fap(disgust, 55) < 0 and fap(disgust, 63) > 0
    assert fap(disgust, 31) <= 0
    surprise = e["surprise"]
    assert all(fap(surprise, k) >= 200 for k in range(31, 37))
    assert fap(surprise, 19) < 0 and fap(surprise, 21) == 0 and fap(surprise, 3) > 0


# ---- blends --------------------------------------------------------------------------------------

def test_viseme_blend_by_hand():
    pp, aa = VISEME_PROFILES["mpeg4"]["PP"], VISEME_PROFILES["mpeg4"]["AA"]
    assert np.array_equal(viseme_blend("AA", "PP", 63), aa)
    assert np.array_equal(viseme_blend("AA", "PP", 0), pp)
    mix = viseme_blend(10, 1, 31)                              # codes: 10 = AA, 1 = PP
    assert mix.dtype == np.float64 and mix.shape == (68,)
    assert mix[2] == pytest.approx(850 * 31 / 63 + 40 * 32 / 63)
    assert np.allclose(viseme_blend(10, 0, 21), aa / 3)
    assert np.allclose(viseme_blend("a", "none", 63, set="zh"), VISEME_PROFILES["zh"]["a"])


def test_expression_blend_by_hand():
    joy, sad = EXPRESSION_PROFILES["joy"], EXPRESSION_PROFILES["sadness"]
    assert np.array_equal(expression_blend("joy", 63, "neutral", 0), joy)
    assert np.array_equal(expression_blend(1, 0, 2, 63), sad)
    both = expression_blend(1, 63, 2, 63)                      # intensities need not add to 63
    assert np.array_equal(both, joy + sad)
    assert expression_blend("joy", 31, 0, 0)[58] == pytest.approx(fap(joy, 59) * 31 / 63)


def test_extra_expressions_are_named_only(monkeypatch):
    smirk = build_expression_profiles(expressions("joy,59,1", "anger,31,-1", "smirk,59,120"), STANDARD)["smirk"]
    monkeypatch.setitem(EXPRESSION_PROFILES, "smirk", smirk)
    assert expression_blend("smirk", 63, 0, 0)[58] == 120
    with pytest.raises(ValueError, match="out of range 0..6"):
        expression_blend(7, 63, 0, 0)


@pytest.mark.parametrize("call, message", [
    (lambda: viseme_blend(15, 0, 10), r"viseme select 15 out of range 0..14"),
    (lambda: viseme_blend(-1, 0, 10), r"viseme select -1 out of range 0..14"),
    (lambda: viseme_blend("XX", 0, 10), r"'XX' is not in set 'mpeg4'"),
    (lambda: viseme_blend(1, 0, 64), r"viseme blend 64 out of range 0..63"),
    (lambda: viseme_blend(1, 0, 31.5), r"viseme blend 31.5 is not an integer in 0..63"),
    (lambda: viseme_blend(2.0, 0, 10), r"viseme select 2.0 out of range 0..14"),
    (lambda: viseme_blend(1, 0, 10, set="zh"), r"FAP 1 codes of the mpeg4 set"),
    (lambda: viseme_blend("a", "none", 10, set="fr"), r"unknown viseme set 'fr'"),
    (lambda: expression_blend(7, 10, 0, 0), r"expression select 7 out of range 0..6"),
    (lambda: expression_blend(1, 10, "glee", 0), r"unknown expression 'glee'"),
    (lambda: expression_blend(1, -1, 0, 0), r"expression intensity1 -1 out of range 0..63"),
    (lambda: expression_blend(1, 1, 0, 99), r"expression intensity2 99 out of range 0..63"),
])
def test_blend_errors_name_value_and_range(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def random_frames(n: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    vis = np.stack([rng.integers(0, 15, n), rng.integers(0, 15, n), rng.integers(0, 64, n),
                    rng.integers(0, 2, n)], axis=1).astype(np.int32)
    exp = np.stack([rng.integers(0, 7, n), rng.integers(0, 64, n), rng.integers(0, 7, n),
                    rng.integers(0, 64, n), rng.integers(0, 2, n), rng.integers(0, 2, n)], axis=1).astype(np.int32)
    return vis, exp


def test_expand_high_level_matches_scalar_blends():
    vis, exp = random_frames(500)
    got = expand_high_level(vis, exp)
    assert got.shape == (500, 68) and got.dtype == np.float64
    for k in range(len(vis)):
        want = viseme_blend(*(int(x) for x in vis[k, :3])) + expression_blend(*(int(x) for x in exp[k, :4]))
        assert np.allclose(got[k], want), k
    assert not got[:, :2].any()


def test_expand_high_level_zero_rows_and_errors():
    assert not expand_high_level(np.zeros((3, 4), np.int32), np.zeros((3, 6), np.int32)).any()
    assert expand_high_level(np.zeros((0, 4), np.int32), np.zeros((0, 6), np.int32)).shape == (0, 68)
    vis, exp = random_frames(10)
    bad = vis.copy()
    bad[4, 2] = 79
    with pytest.raises(SpecError, match="frame 4: FAP 1 viseme_blend = 79 is out of range 0..78") as info:
        expand_high_level(bad, exp)
    assert isinstance(info.value, MpegFaError) and isinstance(info.value, ValueError)
    assert info.value.where == "frame 4" and "63" in info.value.hint
    over = vis.copy()
    over[:, 2], vis[:, 2] = 64, 63  # 63 quantised at fap_quant 2 comes back as 64: full scale
    np.testing.assert_array_equal(expand_high_level(over, exp), expand_high_level(vis, exp))
    bad = exp.copy()
    bad[6, 2] = 9
    with pytest.raises(SpecError, match=r"frame 6: FAP 2 expression_select2 = 9 is not an expression \(0..6\)"):
        expand_high_level(vis, bad)
    with pytest.raises(SpecError, match=r"\(n, 4\)"):
        expand_high_level(vis[:, :3], exp)
    with pytest.raises(ValueError, match=r"\(n, 4\)"):
        expand_high_level(vis[:5], exp)
    with pytest.raises(ValueError, match="integers"):
        expand_high_level(vis.astype(float), exp)


# ---- Chinese visemes -----------------------------------------------------------------------------

def test_every_initial_once():
    for initial in INITIALS:
        owners = [v.name for v in CHINESE_VISEMES if initial in v.pinyin]
        assert len(owners) == 1, (initial, owners)
        assert CHINESE_VISEMES[ZH_NAMES.index(owners[0])].kind in ("initial", "both")


def test_every_final_once_under_its_main_vowel():
    for final in FINALS:
        owners = [v.name for v in CHINESE_VISEMES if final in v.pinyin]
        assert len(owners) == 1, (final, owners)
    assert CHINESE_VISEME_BY_PINYIN["iao"] == "a" and CHINESE_VISEME_BY_PINYIN["iong"] == "o"
    assert CHINESE_VISEME_BY_PINYIN["uei"] == "e" and CHINESE_VISEME_BY_PINYIN["vn"] == "uv"
    assert CHINESE_VISEME_BY_PINYIN["er"] == "r"


def test_glides_endings_and_apical_syllables():
    want = {"i-": "i", "u-": "uv", "v-": "uv", "-i": "i", "-o": "o", "-u": "uv", "-n": "n", "-ng": "ng",
            "-r": "r", "zi": "zcs", "ci": "zcs", "si": "zcs", "zhi": "zhchsh", "chi": "zhchsh",
            "shi": "zhchsh", "ri": "r"}
    for unit, name in want.items():
        assert CHINESE_VISEME_BY_PINYIN[unit] == name, unit
    units = set(INITIALS) | set(FINALS) | set(want)
    assert set(CHINESE_VISEME_BY_PINYIN) == units                 # nothing unexplained listed


def test_chinese_viseme_classes():
    kinds = {v.name: v.kind for v in CHINESE_VISEMES}
    assert all(kinds[n] == "initial" for n in ("bpm", "dtnl", "f", "gkh", "jqx"))
    assert all(kinds[n] == "final" for n in ("a", "e", "o", "n", "ng"))
    assert all(kinds[n] == "both" for n in ("i", "uv", "r", "zcs", "zhchsh"))
    assert all(v.description for v in CHINESE_VISEMES)


def test_module_has_no_loose_names():
    assert set(profiles.__all__) <= set(dir(profiles))


@pytest.mark.parametrize("fap,column,value,message", [
    (1, 0, 20, "frame 12: FAP 1 viseme_select1 = 20 is not a viseme (0..14)"),
    (1, 1, -1, "frame 12: FAP 1 viseme_select2 = -1 is not a viseme (0..14)"),
    (1, 3, 2, "frame 12: FAP 1 viseme_def = 2 is not a flag (0 or 1)"),
    (2, 1, 99, "frame 12: FAP 2 expression_intensity1 = 99 is out of range 0..78"),
    (2, 3, -5, "frame 12: FAP 2 expression_intensity2 = -5 is out of range 0..78"),
    (2, 4, 3, "frame 12: FAP 2 init_face = 3 is not a flag (0 or 1)"),
])
def test_expand_high_level_names_the_frame_and_field(fap, column, value, message):
    vis, exp = np.zeros((20, 4), np.int32), np.zeros((20, 6), np.int32)
    (vis if fap == 1 else exp)[12, column] = value
    (vis if fap == 1 else exp)[15, column] = value  # the first bad frame is the one named
    with pytest.raises(SpecError) as info:
        expand_high_level(vis, exp)
    assert str(info.value).startswith(message + " (")
    assert info.value.where == "frame 12" and info.value.hint


def test_high_level_problem_points_at_the_field():
    assert high_level_problem(1, [3, 4, 63, 0]) is None
    assert high_level_problem(2, [6, 78, 0, 0, 1, 1]) is None
    index, problem, hint = high_level_problem(2, [1, 10, 7, 0, 0, 0])
    assert index == 2 and problem == "FAP 2 expression_select2 = 7 is not an expression (0..6)" and hint


def test_blend_errors_are_spec_errors():
    with pytest.raises(SpecError, match="viseme select 15 out of range"):
        viseme_blend(15, 0, 10)
    with pytest.raises(SpecError, match="unknown expression"):
        expression_blend("glee", 10, 0, 0)
