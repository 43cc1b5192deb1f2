"""What each viseme and expression looks like as low-level FAPs: our tables, not the standard's.

FAP 1 and FAP 2 only *name* visemes and expressions (select, blend, intensity);
ISO/IEC 14496-2 leaves their low-level FAP values to each decoder. The encoder
(text -> speech -> FAPs) and the face engine must agree on them, or "AA" sent by
one would look like something else on the other, so both read the same data
files: ``spec/viseme_faps.csv``, ``spec/expression_faps.csv`` and
``spec/chinese_visemes.csv`` (see the last section of ``spec/README.md``).

Every profile is a read-only int32 array of 68 FAPU integers (index ``i`` is FAP
``i + 1``; FAP 1 and 2 are 0) at full strength, i.e. blend or intensity 63. The
blends below follow the standard's formulas and return float64, because a blend
of integers is not an integer and rounding is the caller's choice.
"""
from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from mpeg4fa.spec import EXPRESSIONS, FAPS, FULL_INTENSITY, HIGH_LEVEL_FIELDS, N_FAPS, VISEMES
from mpeg4fa.spec._load import check, read_table, split_list
from mpeg4fa.spec.errors import SpecError

__all__ = [
    "ChineseViseme", "CHINESE_VISEMES", "CHINESE_VISEME_BY_PINYIN", "VISEME_PROFILES",
    "EXPRESSION_PROFILES", "viseme_blend", "expression_blend", "expand_high_level",
    "build_viseme_profiles", "build_expression_profiles", "high_level_problem",
    "first_high_level_fault", "SpecError",
]

MPEG4 = "mpeg4"
"""Name of the viseme set that FAP 1's select codes 0..14 index (``visemes.csv``)."""

_RANGE = {(f.fap, f.field): (f.i_min, f.i_max) for f in HIGH_LEVEL_FIELDS}
_FULL = FULL_INTENSITY
"""Blend or intensity that means "all of it" (63): profiles are stored at this strength."""
check(_RANGE[(1, "select1")] == (0, len(VISEMES) - 1), "viseme select range must cover visemes.csv")
check(_RANGE[(2, "select1")] == (0, len(EXPRESSIONS) - 1),
      "expression select range must cover expressions.csv")

_NAME = re.compile(r"[a-z][a-z0-9_]*")
_INTEGER = re.compile(r"[+-]?[0-9]+")
_KINDS = ("initial", "final", "both")


@dataclass(frozen=True)
class ChineseViseme:
    """One Mandarin viseme (a row of ``chinese_visemes.csv``).

    ``pinyin`` lists the units it shows: initials (``b``), finals in pypinyin's
    strict spelling with ü written ``v`` (``ian``), whole syllables whose
    apical i keeps the initial's shape (``zhi``), glides (``i-``) and endings
    (``-ng``). A final is listed under the viseme of its main vowel; it is
    spoken as glide, main vowel, ending (``iao`` -> i, a, o).
    """

    name: str
    kind: str
    """``initial``, ``final`` or ``both``: which part of a syllable it serves."""
    pinyin: tuple[str, ...]
    description: str


def _chinese_visemes() -> tuple[ChineseViseme, ...]:
    rows = read_table("chinese_visemes.csv", "viseme,class,pinyin,description")
    result = tuple(
        ChineseViseme(name=r["viseme"], kind=r["class"], pinyin=split_list(r["pinyin"]),
                      description=r["description"])
        for r in rows
    )
    for line, v in enumerate(result, start=2):
        check(_NAME.fullmatch(v.name) is not None and v.name != "none",
              f"chinese_visemes.csv line {line}: bad viseme name {v.name!r}")
        check(v.kind in _KINDS, f"chinese_visemes.csv line {line}: class {v.kind!r} not in {_KINDS}")
        check(len(v.pinyin) > 0, f"chinese_visemes.csv line {line}: {v.name} covers no pinyin")
    names = [v.name for v in result]
    check(len(set(names)) == len(names), "chinese_visemes.csv: a viseme is listed twice")
    return result


CHINESE_VISEMES = _chinese_visemes()
"""The Mandarin viseme set ``zh``, in file order."""


def _by_pinyin() -> dict[str, str]:
    result: dict[str, str] = {}
    for v in CHINESE_VISEMES:
        for unit in v.pinyin:
            check(unit not in result,
                  f"chinese_visemes.csv: {unit!r} is in both {result.get(unit)} and {v.name}")
            result[unit] = v.name
    return result


CHINESE_VISEME_BY_PINYIN = _by_pinyin()
"""Pinyin unit (initial, final, whole syllable, ``i-`` glide, ``-n`` ending) -> zh viseme name."""

_SET_NAMES: dict[str, tuple[str, ...]] = {
    MPEG4: tuple(v.name for v in VISEMES),
    "zh": ("none",) + tuple(v.name for v in CHINESE_VISEMES),
}
"""Names each viseme set may use, in order; ``none`` (the rest pose) is first in every set."""


def _frozen_profile(values: Mapping[int, int]) -> np.ndarray:
    arr = np.zeros(N_FAPS, dtype=np.int32)
    for fap, value in values.items():
        arr[fap - 1] = value
    arr.flags.writeable = False
    return arr


def _fap_value(row: Mapping[str, str], where: str) -> tuple[int, int]:
    """FAP number and value of one row, checked: FAP 3..68, integers, sign of unidirectional FAPs."""
    fap_text, value_text = row["fap"], row["value"]
    check(_INTEGER.fullmatch(fap_text) is not None, f"{where}: FAP {fap_text!r} is not an integer")
    check(_INTEGER.fullmatch(value_text) is not None, f"{where}: value {value_text!r} is not an integer")
    fap, value = int(fap_text), int(value_text)
    check(3 <= fap <= N_FAPS, f"{where}: FAP {fap} is not a low-level FAP (3..{N_FAPS})")
    check(-(2**31) <= value < 2**31, f"{where}: value {value} does not fit int32")
    info = FAPS[fap - 1]
    check(not (info.unidirectional and value < 0),
          f"{where}: FAP {fap} ({info.name}) is unidirectional, value {value} must be >= 0")
    return fap, value


def build_viseme_profiles(
    rows: Iterable[Mapping[str, str]], set_names: Mapping[str, Sequence[str]],
    source: str = "viseme_faps.csv",
) -> dict[str, dict[str, np.ndarray]]:
    """Check the long-form rows ``set,viseme,fap,value`` and turn them into one array per viseme.

    ``set_names`` gives each set's names in order; every name but ``none``
    needs at least one row (a forgotten viseme would otherwise read as the rest
    pose) and ``none`` may have none. Raises ``ValueError`` with the line.
    Separate from the loader so that tests can feed it bad rows.
    """
    values: dict[tuple[str, str], dict[int, int]] = {}
    for line, row in enumerate(rows, start=2):
        where = f"{source} line {line}"
        set_name, name = row["set"], row["viseme"]
        check(set_name in set_names,
              f"{where}: unknown viseme set {set_name!r} (known: {', '.join(set_names)})")
        check(name in set_names[set_name], f"{where}: {name!r} is not a viseme of set {set_name!r}")
        check(name != "none", f"{where}: 'none' is the rest pose and takes no rows")
        fap, value = _fap_value(row, where)
        profile = values.setdefault((set_name, name), {})
        check(fap not in profile, f"{where}: FAP {fap} of {set_name}/{name} given twice")
        if value:
            profile[fap] = value
    result: dict[str, dict[str, np.ndarray]] = {}
    for set_name, names in set_names.items():
        for name in names:
            check(name == "none" or (set_name, name) in values,
                  f"{source}: viseme {set_name}/{name} has no rows")
        result[set_name] = {name: _frozen_profile(values.get((set_name, name), {})) for name in names}
    return result


def build_expression_profiles(
    rows: Iterable[Mapping[str, str]], standard: Sequence[str], source: str = "expression_faps.csv",
) -> dict[str, np.ndarray]:
    """Check the long-form rows ``expression,fap,value`` and turn them into one array per expression.

    ``standard`` is the expressions.csv order; its first name (neutral) is the
    zero face and takes no rows, each other one needs rows. A name outside it is
    an extra profile (e.g. a house "smirk"), kept after the standard ones in the
    order first seen, so that new expressions are added as data alone; such
    names must be lower-case identifiers so a typo like ``Joy`` does not hide.
    """
    neutral = standard[0]
    values: dict[str, dict[int, int]] = {}
    for line, row in enumerate(rows, start=2):
        where = f"{source} line {line}"
        name = row["expression"]
        check(_NAME.fullmatch(name) is not None, f"{where}: bad expression name {name!r}")
        check(name != neutral, f"{where}: {neutral!r} is the zero face and takes no rows")
        fap, value = _fap_value(row, where)
        profile = values.setdefault(name, {})
        check(fap not in profile, f"{where}: FAP {fap} of {name} given twice")
        if value:
            profile[fap] = value
    for name in standard[1:]:
        check(name in values, f"{source}: expression {name} has no rows")
    extras = [name for name in values if name not in standard]
    return {name: _frozen_profile(values.get(name, {})) for name in (*standard, *extras)}


VISEME_PROFILES: dict[str, dict[str, np.ndarray]] = build_viseme_profiles(
    read_table("viseme_faps.csv", "set,viseme,fap,value"), _SET_NAMES)
"""Viseme set (``mpeg4``, ``zh``) -> name -> FAP values at blend 63; ``none`` is all zero."""

EXPRESSION_PROFILES: dict[str, np.ndarray] = build_expression_profiles(
    read_table("expression_faps.csv", "expression,fap,value"), tuple(e.name for e in EXPRESSIONS))
"""Expression name -> FAP values at intensity 63: neutral (zero), the six standard ones, then extras."""

# Stacked in select-code order so a whole stream is one fancy-indexing gather.
_VISEME_STACK = np.stack([VISEME_PROFILES[MPEG4][v.name] for v in VISEMES]).astype(np.float64)
_EXPRESSION_STACK = np.stack([EXPRESSION_PROFILES[e.name] for e in EXPRESSIONS]).astype(np.float64)
_VISEME_STACK.flags.writeable = False
_EXPRESSION_STACK.flags.writeable = False


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _level(value: object, field: str) -> int:
    """A blend or intensity, checked against the field's range 0..63."""
    lo, hi = _RANGE[(1, "blend")]
    if not _is_int(value):
        raise SpecError(f"{field} {value!r} is not an integer in {lo}..{hi}")
    if not lo <= value <= hi:
        raise SpecError(f"{field} {value!r} out of range {lo}..{hi}")
    return int(value)


def _viseme(select: int | str, set_name: str) -> np.ndarray:
    if set_name not in VISEME_PROFILES:
        raise SpecError(f"unknown viseme set {set_name!r} (known: {', '.join(VISEME_PROFILES)})")
    profiles = VISEME_PROFILES[set_name]
    if isinstance(select, str):
        if select not in profiles:
            raise SpecError(f"viseme {select!r} is not in set {set_name!r} (known: {', '.join(profiles)})")
        return profiles[select]
    lo, hi = _RANGE[(1, "select1")]
    if set_name != MPEG4:
        raise SpecError(f"viseme select {select!r}: numbers are FAP 1 codes of the {MPEG4} set; "
                         f"name a viseme of set {set_name!r} instead")
    if not _is_int(select) or not lo <= select <= hi:
        raise SpecError(f"viseme select {select!r} out of range {lo}..{hi} (or a viseme name)")
    return profiles[VISEMES[int(select)].name]


def _expression(select: int | str) -> np.ndarray:
    if isinstance(select, str):
        if select not in EXPRESSION_PROFILES:
            raise SpecError(f"unknown expression {select!r} (known: {', '.join(EXPRESSION_PROFILES)})")
        return EXPRESSION_PROFILES[select]
    lo, hi = _RANGE[(2, "select1")]
    if not _is_int(select) or not lo <= select <= hi:
        raise SpecError(f"expression select {select!r} out of range {lo}..{hi} (or an expression name)")
    return EXPRESSION_PROFILES[EXPRESSIONS[int(select)].name]


def viseme_blend(select1: int | str, select2: int | str, blend: int, set: str = MPEG4) -> np.ndarray:
    """FAP values (68, float64) of one FAP 1: ``v1 * blend/63 + v2 * (1 - blend/63)``.

    Selects are FAP 1 codes 0..14 (visemes.csv order, ``mpeg4`` set only) or
    names of ``set``; ``blend`` is 0..63, so 63 shows ``select1`` alone and 0
    ``select2`` alone, as the standard defines it.
    """
    v1, v2 = _viseme(select1, set), _viseme(select2, set)
    w = _level(blend, "viseme blend") / _FULL
    return v1 * w + v2 * (1.0 - w)


def expression_blend(select1: int | str, intensity1: int, select2: int | str, intensity2: int) -> np.ndarray:
    """FAP values (68, float64) of one FAP 2: ``e1 * intensity1/63 + e2 * intensity2/63``.

    Selects are codes 0..6 (expressions.csv order) or any name in
    :data:`EXPRESSION_PROFILES`; the intensities are independent (they need not
    add up to 63), as the standard defines it.
    """
    e1, e2 = _expression(select1), _expression(select2)
    i1, i2 = _level(intensity1, "expression intensity1"), _level(intensity2, "expression intensity2")
    return e1 * (i1 / _FULL) + e2 * (i2 / _FULL)


_ROUNDING = 15
"""How far above full strength (63) a legal stream brings a blend or intensity back: fap_quant up
to 31 with the reference rounding adds up to 31 // 2 (64 at q = 2, 65 at q = 5)."""

_LIMITS: dict[int, tuple[tuple[str, int, int, str], ...]] = {
    fap: tuple((f"{part}_{f.field}", f.i_min, f.i_max + _ROUNDING, "level") if f.quantised
               else (f"{part}_{f.field}", f.i_min, f.i_max, "select")
               for f in HIGH_LEVEL_FIELDS if f.fap == fap)
    + tuple((name, 0, 1, "flag") for name in flags)
    for fap, part, flags in ((1, "viseme", ("viseme_def",)), (2, "expression", ("init_face", "expression_def")))
}
"""Per FAP 1/2, the fields of a ``FapStream`` row (viseme: select1, select2, blend, def; expression:
select1, intensity1, select2, intensity2, init_face, def) as (syntax name, lowest, highest, kind):
the arithmetic-coded fields from ``high_level_fields.csv``, then the one-bit flags. The one rule for
these fields: streams (:func:`expand_high_level`) and ``.fap`` files (:mod:`mpeg4fa.formats.fap_text`)
are checked against it."""
_NAMED = {1: "a viseme", 2: "an expression"}


def high_level_problem(fap: int, row) -> tuple[int, str, str] | None:
    """The first field of one FAP 1 (``fap=1``) or FAP 2 row outside its range, as (index, problem,
    hint); None when every field fits. Used by readers that can point at the offending token."""
    for k, (name, lo, hi, kind) in enumerate(_LIMITS[fap]):
        value = int(row[k])
        if lo <= value <= hi:
            continue
        if kind == "select":
            table = "visemes.csv" if fap == 1 else "expressions.csv"
            return k, f"FAP {fap} {name} = {value} is not {_NAMED[fap]} ({lo}..{hi})", f"selects index {table}"
        if kind == "flag":
            return k, f"FAP {fap} {name} = {value} is not a flag (0 or 1)", "a one-bit field"
        return k, f"FAP {fap} {name} = {value} is out of range {lo}..{hi}", \
            f"blend and intensity run {lo}..{_FULL}; a quantised stream may bring {_FULL} back as up to {hi}"
    return None


def first_high_level_fault(fap: int, table: np.ndarray) -> tuple[int, int, str, str] | None:
    """The first frame of a stream's FAP 1 (``viseme``, ``fap=1``) or FAP 2 (``expression``) array
    whose fields leave their ranges, as (frame, field index, problem, hint); None if all fit."""
    limits = _LIMITS[fap]
    lo = np.array([low for _, low, _, _ in limits])
    hi = np.array([high for _, _, high, _ in limits])
    bad = np.flatnonzero(((table < lo) | (table > hi)).any(axis=1))
    if not bad.size:
        return None
    k = int(bad[0])
    index, problem, hint = high_level_problem(fap, table[k])  # type: ignore[misc]
    return k, index, problem, hint


def _check_rows(fap: int, table: np.ndarray) -> None:
    """Raise a :class:`SpecError` at the first frame whose FAP 1/2 fields leave their ranges."""
    fault = first_high_level_fault(fap, table)
    if fault is not None:
        k, _, problem, hint = fault
        raise SpecError(problem, where=f"frame {k}", hint=hint)


def expand_high_level(viseme: np.ndarray, expression: np.ndarray) -> np.ndarray:
    """Low-level FAP values (n, 68, float64) that FAP 1 plus FAP 2 stand for, frame by frame.

    Takes a :class:`~mpeg4fa.fba.stream.FapStream`'s ``viseme`` (n, 4: select1,
    select2, blend, def) and ``expression`` (n, 6: select1, intensity1,
    select2, intensity2, init_face, def) arrays. All-zero rows (FAP 1/2 not
    sent) give zeros. The def and init_face flags are ignored: our decoder does
    not let a stream redefine the tables. Same numbers as :func:`viseme_blend`
    + :func:`expression_blend`, but gathered from stacked profile matrices by
    fancy indexing, because streams run to thousands of frames and a Python
    loop per frame would dominate decoding.
    """
    vis, exp = np.asarray(viseme), np.asarray(expression)
    if vis.ndim != 2 or vis.shape[1] != 4 or exp.ndim != 2 or exp.shape[1] != 6 or len(vis) != len(exp):
        raise SpecError(f"viseme must be (n, 4) and expression (n, 6), got {vis.shape} and {exp.shape}")
    if not (np.issubdtype(vis.dtype, np.integer) and np.issubdtype(exp.dtype, np.integer)):
        raise SpecError(f"viseme and expression fields must be integers, got {vis.dtype} and {exp.dtype}")
    # Blend and intensities may come back from a quantised stream a little above 63 (_ROUNDING): clipped.
    _check_rows(1, vis)
    _check_rows(2, exp)
    w = np.clip(vis[:, 2, None], 0, _FULL) / _FULL
    out = _VISEME_STACK[vis[:, 0]] * w + _VISEME_STACK[vis[:, 1]] * (1.0 - w)
    out += _EXPRESSION_STACK[exp[:, 0]] * (np.clip(exp[:, 1, None], 0, _FULL) / _FULL)
    out += _EXPRESSION_STACK[exp[:, 2]] * (np.clip(exp[:, 3, None], 0, _FULL) / _FULL)
    return out
