"""The MPEG-4 face and body animation tables, loaded once from ``spec/*.csv``.

The numbers live only in the data files of the top-level ``spec/`` folder (see
its README for sources and confidence); this module turns them into records
and numpy arrays at import so the codec never retypes a table. Arrays are
read-only because every module shares them. Array index ``i`` is FAP ``i + 1``
and BAP ``i + 1``.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.spec._load import check, opt_float, opt_int, opt_str, read_table, split_list
from mpeg4fa.spec._records import Expression, Fap, Fapu, FeaturePoint, HighLevelField, Viseme

__all__ = [
    "Fap", "FeaturePoint", "Fapu", "Viseme", "Expression", "HighLevelField",
    "N_FAPS", "N_BAPS", "N_ISO_BAPS", "N_FAP_GROUPS", "N_BAP_GROUPS", "FULL_INTENSITY", "ANGLE_UNIT", "AU_PER_RADIAN",
    "FAPU_NAMES", "FEATURE_POINT_MIRROR", "FAPS", "FAP_BY_NAME", "QUANT_STEP", "I_MAX_DEFAULT", "P_MAX_DEFAULT",
    "FAP_GROUP", "FAP_GROUP_SLICES", "FAP_PARTNERS", "HIGH_LEVEL_FIELDS", "FEATURE_POINTS", "FAPU",
    "VISEMES", "EXPRESSIONS", "BAP_GROUPS", "BAP_QUANT_STEP", "BAP_QUANT_STEP_ALT",
    "BAP_PRED_SCALE",
]

def _frozen(values: list[int]) -> np.ndarray:
    arr = np.array(values, dtype=np.int32)
    arr.flags.writeable = False
    return arr


FAPS: tuple[Fap, ...] = tuple(
    Fap(
        number=int(r["fap"]), name=r["name"], description=r["description"],
        fapu=opt_str(r["fapu"]), direction=opt_str(r["direction"]),
        unidirectional=None if not r["unidirectional"] else r["unidirectional"] == "1",
        group=int(r["group"]), feature_point=split_list(r["feature_point"]),
        quant_step=int(r["quant_step"]), i_max=opt_int(r["i_max"]), p_max=opt_int(r["p_max"]),
        lr_partner=opt_int(r["lr_partner"]), io_partner=opt_int(r["io_partner"]), notes=r["notes"],
    )
    for r in read_table(
        "faps.csv",
        "fap,name,description,fapu,direction,unidirectional,group,feature_point,"
        "quant_step,i_max,p_max,lr_partner,io_partner,notes",
    )
)
"""All 68 FAPs; ``FAPS[k]`` is FAP ``k + 1``."""
N_FAPS = len(FAPS)
"""68: FAP 1 (viseme), FAP 2 (expression) and the 66 low-level FAPs."""
check([f.number for f in FAPS] == list(range(1, N_FAPS + 1)), "faps.csv must list FAP 1..n in order")

FAP_BY_NAME: dict[str, Fap] = {f.name: f for f in FAPS}
"""FAPs by their name, e.g. ``"open_jaw"``."""

QUANT_STEP = _frozen([f.quant_step for f in FAPS])
"""Per-FAP quantiser step (QP); the coded step is ``QUANT_STEP * fap_quant``."""
I_MAX_DEFAULT = _frozen([f.i_max or 0 for f in FAPS])
"""Default intra range magnitudes in quantised units (0 for FAP 1, 2)."""
P_MAX_DEFAULT = _frozen([f.p_max or 0 for f in FAPS])
"""Default P range magnitudes in quantised units (0 for FAP 1, 2)."""
FAP_GROUP = _frozen([f.group for f in FAPS])
"""FAP group number (1..10) of each FAP."""


def _group_slices() -> tuple[tuple[int, int], ...]:
    rows = read_table("fap_groups.csv", "group,first_fap,last_fap,name")
    check([int(r["group"]) for r in rows] == list(range(1, len(rows) + 1)), "groups out of order")
    slices = tuple((int(r["first_fap"]) - 1, int(r["last_fap"])) for r in rows)
    ends = [0] + [stop for _, stop in slices]
    check([start for start, _ in slices] + [N_FAPS] == ends, "FAP groups must tile FAP 1..68")
    return slices


FAP_GROUP_SLICES = _group_slices()
"""Half-open 0-based column range of each FAP group; the mask is sent per group."""
N_FAP_GROUPS = len(FAP_GROUP_SLICES)
"""10: the groups a frame's FAP mask is sent by (``fap_groups.csv``)."""
check(set(FAP_GROUP.tolist()) == set(range(1, N_FAP_GROUPS + 1)), "faps.csv groups must be 1..n")


def _counterparts() -> np.ndarray:
    partner = np.full((N_FAPS, 2), -1, dtype=np.int32)
    for record in FAPS:
        for k, other in enumerate((record.lr_partner, record.io_partner)):
            if other is not None:
                check(1 <= other <= N_FAPS and other != record.number, f"FAP {record.number}: partner {other}")
                partner[record.number - 1, k] = other - 1
    check(all(partner[p, k] == i for i in range(N_FAPS) for k in range(2) if (p := partner[i, k]) >= 0),
          "faps.csv: lr_partner and io_partner must name each other")
    partner.flags.writeable = False
    return partner


FAP_PARTNERS = _counterparts()
"""``(68, 2)`` 0-based columns of each FAP's interpolation counterparts (-1: none): left/right
(``lr_partner`` in faps.csv), then inner/outer lip (``io_partner``: FAPs 4-13 <-> 51-60). Mask
type 2 copies an unsent FAP from the first one that is sent; the encoder leaves out what the
decoder can copy."""

HIGH_LEVEL_FIELDS: tuple[HighLevelField, ...] = tuple(
    HighLevelField(
        fap=int(r["fap"]), field=r["field"], i_min=int(r["i_min"]), i_max=int(r["i_max"]),
        p_min=int(r["p_min"]), p_max=int(r["p_max"]), quantised=r["quantised"] == "1",
    )
    for r in read_table("high_level_fields.csv", "fap,field,i_min,i_max,p_min,p_max,quantised")
)
"""The arithmetic-coded fields of FAP 1 then FAP 2, in bitstream order, with their fixed ranges."""
FULL_INTENSITY: int = next(f.i_max for f in HIGH_LEVEL_FIELDS if (f.fap, f.field) == (1, "blend"))
"""63: the viseme blend or expression intensity that means "all of it" (the top of their range)."""
check(all(f.i_min == 0 and f.i_max == FULL_INTENSITY for f in HIGH_LEVEL_FIELDS if f.quantised),
      "blend and intensities must share one range 0..full")

FEATURE_POINTS: tuple[FeaturePoint, ...] = tuple(
    FeaturePoint(
        label=r["fp"], group=int(r["group"]), description=r["description"],
        moved_by_faps=tuple(int(x) for x in split_list(r["moved_by_faps"])),
        fapu_role=split_list(r["fapu_role"]), side=opt_str(r["side"]), mirror=opt_str(r["mirror"]),
    )
    for r in read_table("feature_points.csv", "fp,group,description,moved_by_faps,fapu_role,side,mirror")
)
"""The 84 feature points of groups 2..11, in label order."""


def _mirrors() -> dict[str, str]:
    by_label = {fp.label: fp for fp in FEATURE_POINTS}
    for fp in FEATURE_POINTS:
        check(fp.side in (None, "left", "right"), f"feature point {fp.label}: side {fp.side!r}")
        check((fp.side is None) == (fp.mirror is None), f"feature point {fp.label}: a side needs a mirror")
        twin = by_label.get(fp.mirror) if fp.mirror else None
        check(fp.mirror is None or (twin is not None and twin.mirror == fp.label and twin.side != fp.side),
              f"feature point {fp.label}: mirror {fp.mirror} must name it back, on the other side")
    return {fp.label: fp.mirror for fp in FEATURE_POINTS if fp.mirror}


FEATURE_POINT_MIRROR = _mirrors()
"""Each sided feature point's left/right twin, both ways (3.5 -> 3.6 and 3.6 -> 3.5)."""

FAPU: dict[str, Fapu] = {
    r["fapu"]: Fapu(
        symbol=r["fapu"], name=r["name"], distance=opt_str(r["distance"]), definition=r["definition"],
        point_a=opt_str(r["point_a"]), axis=opt_str(r["axis"]), point_b=opt_str(r["point_b"]),
        divisor=opt_int(r["divisor"]), unit=r["unit"], radians=opt_float(r["radians"]),
    )
    for r in read_table("fapu.csv", "fapu,name,distance,definition,point_a,axis,point_b,divisor,unit,radians")
}
"""The six FAPU by symbol (IRISD, ES, ENS, MNS, MW, AU)."""
FAPU_NAMES: tuple[str, ...] = tuple(f.distance for f in FAPU.values() if f.distance)
"""The five neutral-face distances in ``fapu.csv`` order (IRISD0, ES0, ENS0, MNS0, MW0), the one
order every reader and writer uses (the binary FDP numbers its keys 0..4 in it)."""
_ANGLES = [f for f in FAPU.values() if not f.distance]
check(len(_ANGLES) == 1 and _ANGLES[0].radians is not None and _ANGLES[0].point_a is None,
      "fapu.csv: exactly one unit (AU) is an angle, given in radians, not measured")
ANGLE_UNIT: float = _ANGLES[0].radians
"""One AU in radians (1e-5): the unit of the rotation FAPs."""
AU_PER_RADIAN: int = round(1.0 / ANGLE_UNIT)
"""AU in one radian (100000), as an exact integer: ``1 / 1e-5`` in floating point is not one."""
check(AU_PER_RADIAN * ANGLE_UNIT == 1.0, "fapu.csv: AU must be one over a whole number of radians")
del _ANGLES

VISEMES: tuple[Viseme, ...] = tuple(
    Viseme(number=int(r["viseme"]), name=r["name"], phonemes=r["phonemes"], examples=r["examples"])
    for r in read_table("visemes.csv", "viseme,name,phonemes,examples")
)
"""Visemes 0..14; ``VISEMES[k]`` is viseme ``k`` (0 = none)."""
check([v.number for v in VISEMES] == list(range(len(VISEMES))), "visemes out of order")

EXPRESSIONS: tuple[Expression, ...] = tuple(
    Expression(number=int(r["expression"]), name=r["name"], description=r["description"])
    for r in read_table("expressions.csv", "expression,name,description")
)
"""Expressions 0..6; ``EXPRESSIONS[k]`` is expression ``k`` (0 = neutral)."""
check([e.number for e in EXPRESSIONS] == list(range(len(EXPRESSIONS))), "expressions out of order")


_BAP_QUANT = read_table("bap_quant.csv", "bap,bqp,bqp_alt")
N_BAPS = len(_BAP_QUANT)
"""296: the 186 ISO BAPs and the 110 visage extension BAPs, one row each in ``bap_quant.csv``."""
check([int(r["bap"]) for r in _BAP_QUANT] == list(range(1, N_BAPS + 1)), "bap_quant.csv must list BAP 1..n")


def _bap_groups() -> tuple[tuple[int, ...], ...]:
    groups: dict[int, list[tuple[int, int]]] = {}
    for r in read_table("bap_groups.csv", "group,position,bap"):
        groups.setdefault(int(r["group"]), []).append((int(r["position"]), int(r["bap"]) - 1))
    check(sorted(groups) == list(range(1, len(groups) + 1)), "BAP groups must be numbered 1..n")
    result = []
    for g in sorted(groups):
        members = sorted(groups[g])
        check([p for p, _ in members] == list(range(1, len(members) + 1)), f"BAP group {g} positions")
        result.append(tuple(b for _, b in members))
    check(sorted(b for grp in result for b in grp) == list(range(N_BAPS)), "each BAP once")
    return tuple(result)


BAP_GROUPS = _bap_groups()
"""The 24 BAP groups as 0-based BAP indices in bitstream order (19 ISO + 5 visage)."""
N_BAP_GROUPS = len(BAP_GROUPS)
"""24: the groups a frame's BAP mask is sent by (``bap_groups.csv``)."""


def _iso_bap_count() -> int:
    """Last ISO BAP (``bap_sets.csv``), checked against the BAP groups: the ISO groups hold exactly BAPs 1..n."""
    sets = {r["set"]: r for r in read_table("bap_sets.csv", "set,first_bap,last_bap,first_group,last_group,note")}
    iso, ext = sets["iso"], sets["extension"]
    last = int(iso["last_bap"])
    check(int(iso["first_bap"]) == 1 and int(ext["first_bap"]) == last + 1 and int(ext["last_bap"]) == N_BAPS,
          "bap_sets.csv: the ISO and extension BAPs must split 1..N_BAPS")
    iso_groups = BAP_GROUPS[int(iso["first_group"]) - 1:int(iso["last_group"])]
    check(sorted(b for g in iso_groups for b in g) == list(range(last)) and int(ext["last_group"]) == N_BAP_GROUPS,
          "bap_sets.csv: the ISO groups must hold exactly the ISO BAPs")
    return last


N_ISO_BAPS = _iso_bap_count()
"""186: the BAPs of ISO/IEC 14496-2 (BAP groups 1..19); BAPs above are the visage extension (``bap_sets.csv``)."""

BAP_QUANT_STEP = _frozen([int(r["bqp"]) for r in _BAP_QUANT])
"""Per-BAP quantiser step (BQP) that real streams decode with (visage "experiment")."""
BAP_QUANT_STEP_ALT = _frozen([int(r["bqp_alt"]) for r in _BAP_QUANT])
"""The BQP table visage labels "standard" but leaves unused; which one ISO specifies is unverified."""
del _BAP_QUANT

BAP_PRED_SCALE = _frozen([int(r["scale"]) for r in read_table("bap_pred_scale.csv", "bap_quant,scale")])
"""Scale by bap_quant 0..31: the BAP step is ``BAP_QUANT_STEP * BAP_PRED_SCALE[bap_quant]``."""

from mpeg4fa.spec.profiles import (  # noqa: E402  (needs the tables above)
    CHINESE_VISEME_BY_PINYIN, CHINESE_VISEMES, EXPRESSION_PROFILES, VISEME_PROFILES, ChineseViseme,
    expand_high_level, expression_blend, viseme_blend,
)
from mpeg4fa.spec.errors import SpecError  # noqa: E402

from mpeg4fa.spec.weights import (  # noqa: E402  (needs the Chinese visemes)
    MANDARIN_DEFAULT_INITIAL_WEIGHT, MANDARIN_INITIAL_WEIGHT, MANDARIN_PART_WEIGHT,
)

__all__ += [
    "MANDARIN_PART_WEIGHT", "MANDARIN_INITIAL_WEIGHT", "MANDARIN_DEFAULT_INITIAL_WEIGHT",
    "ChineseViseme", "CHINESE_VISEMES", "CHINESE_VISEME_BY_PINYIN", "VISEME_PROFILES",
    "EXPRESSION_PROFILES", "viseme_blend", "expression_blend", "expand_high_level", "SpecError",
]
