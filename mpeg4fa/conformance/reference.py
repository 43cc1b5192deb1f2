"""The suite's own reference model of the standard's semantics: what a conforming decoder shows.

A second, deliberately plain implementation of the rules, written from the facts file
(``/work/shared/reference/mpeg4-fba-facts.md``, cited as "facts §n") and ``spec/SYNTAX.md``,
not from ``mpeg4fa.decoded`` and without ``mpeg4fa.face``: expected results computed by the
code under test would pass any bug it has. Loops per frame, so each rule can be read off.

Rules and their confidence ([V] verified on real streams, [S] stated in a source, [M] unverified):

==  =====================================================================  ====  ========================
#   rule                                                                   conf  source
==  =====================================================================  ====  ========================
1   a FAP not sent keeps its previous value; 0 before it is first sent     S     facts §5.3 (mask types)
2   mask type 1 (and 0, 3): unsent FAPs hold (rule 1)                      M     facts §5.3, §8.4
3   mask type 2: an unsent FAP copies its left/right counterpart sent in   M     facts §2 "Interpolation
    the same frame, else its inner/outer lip counterpart (FAPs 4-13 <->          conventions", §8.4;
    51-60), else holds; the copied value is then the FAP's previous              spec FAP_PARTNERS
    value (it holds like a sent one)
4   FAP 1 and FAP 2 hold like the others (last fields sent)                S     facts §4, SYNTAX.md
5   viseme: v1 * blend/63 + v2 * (1 - blend/63)                            S     facts §4.1 (Xface)
6   expression: e1 * i1/63 + e2 * i2/63                                    M     facts §4.2
7   blend/intensity decoded above 63 (quantisation rounding) count as 63   S     SYNTAX.md ranges
8   viseme/expression FAP values: the project's profiles (``spec/``)       M     spec/profiles.py: the
                                                                                 standard leaves them
9   a low-level FAP that has a value (sent, or copied by rule 3, now or    M     facts §4 (init/def
    earlier) overrides the value FAP 1/2 give it                                 semantics [M])
10  no clamping: a decoder shows what was sent                             S     the suite's choice
11  FAPU = key distance on the neutral face / 1024 (``spec/fapu.csv``)     S     facts §1
12  IRISD0 from the right eye (3.2 - 3.4) when 3.1/3.3 are missing         S     facts §1 ("= 3.2.y -
                                                                                 3.4.y")
13  AU = 1e-5 rad, not measured                                            S     facts §1
14  translational FAP: its feature point moves value x FAPU along the      S     facts §1, §2 table
    FAP's direction; FAPs on one point add up
15  axes: +x the face's left, +y up, +z forward (out of the face)          S     facts, "Terminology"
16  dilate_l/r_pupil (29/30, "growing"): the pupil grows, its centre       S     facts §2 (IRISD,
    3.5/3.6 does not move                                                        "growing")
17  eyeball rotations 23-26: centre not given; points not moved            M     facts §2 note [M]
18  head rotations 48-50 about 7.1 (top of spine); points not moved here   S     facts §2, §3 (7.1)
19  tongue_roll 47 (6.3/6.4, "concave upward"): no centre; not moved       M     facts §2
==  =====================================================================  ====  ========================

Real decoders realise some FAPs as motions the table does not spell out (open_jaw as a rotation
of the jaw that drops 2.1 by value x MNS, eyelids on an arc over the eyeball): the component
along the FAP's direction is what rule 14 pins down; the others are the decoder's.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.reference_fapu import fapu_from_points, fapu_units
from mpeg4fa.spec import (
    EXPRESSION_PROFILES, EXPRESSIONS, FAP_GROUP, FAP_PARTNERS, FAPS, FULL_INTENSITY, N_FAP_GROUPS, N_FAPS,
    VISEME_PROFILES, VISEMES,
)

__all__ = ["shown_values", "fapu_from_points", "fapu_units", "feature_point_positions", "rotations",
           "feature_point_tolerance", "TOLERANCE", "DIRECTIONS", "INTERPOLATE"]

INTERPOLATE = 2
"""fap_mask_type 2 (binary 10): unsent FAPs of the group are interpolated (rule 3)."""

TOLERANCE: dict[str, float] = {
    # FAPU units. Sent and held values are integers, exact in any float; only FAP 1/2 expansions
    # (profile x k/63) have fractions. 1e-3 is above float32 rounding of those (|v| < 2000 -> < 2.5e-4)
    # and six-decimal printing, and far below the smallest step a wrong rule makes (1/63 = 0.016).
    "shown": 1e-3,
    # Relative to the face's size (see feature_point_tolerance). One FAPU is at least IRISD0/1024,
    # about 5e-5 of a face, so 1e-6 is 50x below a one-unit error and 15x above float32 rounding.
    "feature_points": 1e-6,
}
"""How far a decoder's output may be from the reference: ``shown`` in FAPU units (absolute),
``feature_points`` as a fraction of the face's size (:func:`feature_point_tolerance`)."""

DIRECTIONS: dict[str, tuple[float, float, float]] = {
    "left": (1.0, 0.0, 0.0), "right": (-1.0, 0.0, 0.0),
    "up": (0.0, 1.0, 0.0), "down": (0.0, -1.0, 0.0),
    "forward": (0.0, 0.0, 1.0),
}
"""Unit vector of each direction word of ``spec/faps.csv`` that moves a point (rule 15). The others
(``growing``: pupil dilation; ``concave upward``: tongue roll) move no point (rules 16, 19)."""

_VISEME_NAMES = tuple(v.name for v in VISEMES)
_EXPRESSION_NAMES = tuple(e.name for e in EXPRESSIONS)


def _check_shapes(mask, values, viseme, expression, group_types) -> int:
    n = len(mask)
    want = {"mask": (mask, N_FAPS), "values": (values, N_FAPS), "viseme": (viseme, 4),
            "expression": (expression, 6), "group_types": (group_types, N_FAP_GROUPS)}
    for name, (arr, width) in want.items():
        if arr.ndim != 2 or arr.shape != (n, width):
            raise ConformanceError(f"{name} must be ({n}, {width}), got {arr.shape}",
                                   hint="one row per frame, as a FapStream holds them")
    return n


def _level(value: int, what: str, frame: int) -> float:
    """A blend or intensity as a fraction of full strength; above 63 (rounding) counts as 63 (rule 7)."""
    if value < 0:
        raise ConformanceError(f"{what} {value} is negative", where=f"frame {frame}")
    return min(int(value), FULL_INTENSITY) / FULL_INTENSITY


def _profile(table: Mapping[str, np.ndarray], names: tuple[str, ...], select: int, what: str, frame: int) -> np.ndarray:
    if not 0 <= select < len(names):
        raise ConformanceError(f"{what} {select} is not in 0..{len(names) - 1}", where=f"frame {frame}")
    return np.asarray(table[names[select]], dtype=np.float64)


def _high_level(vis: np.ndarray, exp: np.ndarray, frame: int) -> np.ndarray:
    """The 68 values FAP 1 plus FAP 2 stand for (rules 5-8)."""
    visemes = VISEME_PROFILES["mpeg4"]
    v1 = _profile(visemes, _VISEME_NAMES, int(vis[0]), "viseme_select1", frame)
    v2 = _profile(visemes, _VISEME_NAMES, int(vis[1]), "viseme_select2", frame)
    blend = _level(int(vis[2]), "viseme_blend", frame)
    e1 = _profile(EXPRESSION_PROFILES, _EXPRESSION_NAMES, int(exp[0]), "expression_select1", frame)
    e2 = _profile(EXPRESSION_PROFILES, _EXPRESSION_NAMES, int(exp[2]), "expression_select2", frame)
    i1 = _level(int(exp[1]), "expression_intensity1", frame)
    i2 = _level(int(exp[3]), "expression_intensity2", frame)
    return v1 * blend + v2 * (1.0 - blend) + e1 * i1 + e2 * i2


def shown_values(mask: np.ndarray, values: np.ndarray, viseme: np.ndarray, expression: np.ndarray,
                 group_types: np.ndarray) -> np.ndarray:
    """``(n, 68)`` float values a conforming decoder shows at each frame (columns 0/1 are 0).

    ``mask`` (n, 68) says what each frame sent, ``values`` (n, 68) the low-level values sent,
    ``viseme`` (n, 4) and ``expression`` (n, 6) the FAP 1/2 fields sent, ``group_types`` (n, 10)
    the fap_mask_type governing each group at each frame (0 none, 1 hold, 2 interpolate, 3 all).
    """
    mask = np.asarray(mask).astype(bool)
    values, viseme, expression = np.asarray(values), np.asarray(viseme), np.asarray(expression)
    group_types = np.asarray(group_types)
    n = _check_shapes(mask, values, viseme, expression, group_types)
    out = np.zeros((n, N_FAPS), dtype=np.float64)
    current = np.zeros(N_FAPS, dtype=np.float64)   # each FAP's value so far (rule 1: 0 before)
    has_value = np.zeros(N_FAPS, dtype=bool)        # sent or copied at some frame so far (rule 9)
    vis = np.zeros(4, dtype=np.int64)               # FAP 1 fields last sent (rule 4)
    exp = np.zeros(6, dtype=np.int64)               # FAP 2 fields last sent
    for k in range(n):
        for col in range(2, N_FAPS):
            if mask[k, col]:
                current[col] = float(values[k, col])
                has_value[col] = True
                continue
            if group_types[k, FAP_GROUP[col] - 1] != INTERPOLATE:
                continue  # rule 2: hold
            for partner in FAP_PARTNERS[col]:  # left/right first, then inner/outer; sent ones only (rule 3)
                if partner >= 0 and mask[k, partner]:
                    current[col] = float(values[k, partner])
                    has_value[col] = True
                    break
        if mask[k, 0]:
            vis = viseme[k].astype(np.int64)
        if mask[k, 1]:
            exp = expression[k].astype(np.int64)
        high = _high_level(vis, exp, k)
        for col in range(2, N_FAPS):
            out[k, col] = current[col] if has_value[col] else high[col]
    return out


def feature_point_tolerance(neutral: Mapping[str, np.ndarray]) -> float:
    """Absolute feature-point tolerance for a face: ``TOLERANCE["feature_points"]`` times its size
    (the diagonal of the neutral feature points' bounding box)."""
    pts = np.array([np.asarray(p, dtype=np.float64) for p in neutral.values()]).reshape(-1, 3)
    if len(pts) < 2:
        raise ConformanceError("a face needs at least two feature points to have a size")
    size = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0)))
    return TOLERANCE["feature_points"] * size


def _translational() -> tuple[tuple[int, str, np.ndarray], ...]:
    """(column, feature point, direction) of every FAP that moves a point (rules 14-16)."""
    rows = []
    for k, record in enumerate(FAPS):
        if record.fapu is None or record.fapu == "AU" or record.direction not in DIRECTIONS:
            continue
        for label in record.feature_point:
            rows.append((k, label, np.array(DIRECTIONS[record.direction])))
    return tuple(rows)


_MOVES = _translational()


def feature_point_positions(neutral: Mapping[str, np.ndarray], shown: np.ndarray) -> dict[str, np.ndarray]:
    """Expected ``(n, 3)`` position per frame of every FAP-driven feature point the face has.

    ``neutral`` maps labels to neutral positions (FDP coordinates), ``shown`` is
    :func:`shown_values`' output. A point moves by value x FAPU unit along each translational
    FAP's direction that drives it (rule 14). Points the face lacks are absent; FAPs whose
    FAPU cannot be measured on this face are skipped; rotations move nothing here (rules 17-19).
    """
    shown = np.asarray(shown, dtype=np.float64)
    if shown.ndim != 2 or shown.shape[1] != N_FAPS:
        raise ConformanceError(f"shown must be (n, {N_FAPS}), got {shown.shape}")
    units = fapu_units(fapu_from_points(neutral))
    result: dict[str, np.ndarray] = {}
    for col, label, direction in _MOVES:
        if label not in neutral or not np.isfinite(units[col]):
            continue
        if label not in result:
            start = np.asarray(neutral[label], dtype=np.float64).reshape(3)
            result[label] = np.repeat(start[None, :], len(shown), axis=0)
        for k in range(len(shown)):
            result[label][k] += shown[k, col] * units[col] * direction
    return result


def rotations(shown: np.ndarray) -> dict[int, np.ndarray]:
    """Angle in radians per frame ``(n,)`` of every rotational (AU) FAP, keyed by FAP number."""
    shown = np.asarray(shown, dtype=np.float64)
    if shown.ndim != 2 or shown.shape[1] != N_FAPS:
        raise ConformanceError(f"shown must be (n, {N_FAPS}), got {shown.shape}")
    units = fapu_units({})
    return {record.number: shown[:, k] * units[k] for k, record in enumerate(FAPS) if record.fapu == "AU"}
