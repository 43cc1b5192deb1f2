"""The suite's own reference model of the standard's semantics: what a conforming decoder shows.

A second, deliberately plain implementation of the rules, written from the facts file
(``../shared/reference/mpeg4-fba-facts.md`` beside the checkout, cited as "facts §n") and ``spec/SYNTAX.md``,
not from ``mpeg4fa.decoded`` and without ``mpeg4fa.face``: expected results computed by the
code under test would pass any bug it has. Loops per frame, so each rule can be read off.

Rules and their confidence ([V] verified on real streams, [S] stated in a source, [M] unverified;
the same as data in :data:`RULES`, so a vector can carry the weakest rule it rests on):

==  =====================================================================  ====  ========================
#   rule                                                                   conf  source
==  =====================================================================  ====  ========================
1   a FAP never sent shows 0: the neutral face                             S     facts §1 (values move
                                                                                 from the neutral face)
2   an unsent FAP keeps its previous value (mask types 0, 1, 3; type 2     M     facts §5.3, §8.4 (hold
    with no counterpart sent)                                                    vs interpolate: memory)
3   mask type 2: an unsent FAP copies its left/right counterpart sent in   M     facts §2 "Interpolation
    the same frame, else its inner/outer lip counterpart (FAPs 4-13 <->          conventions", §8.4;
    51-60), else holds; the copy is then the FAP's previous value                spec FAP_PARTNERS
4   FAP 1 and FAP 2 hold like the others (the fields last sent)            M     as rule 2
5   viseme: v1 * blend/63 + v2 * (1 - blend/63)                            S     facts §4.1 (Xface)
6   expression: e1 * i1/63 + e2 * i2/63                                    M     facts §4.2
7   blend/intensity decoded above 63 (quantisation rounding) count as 63   S     SYNTAX.md (ranges)
8   what a viseme/expression is in FAPs: the project's ``spec/`` profiles  M     spec/profiles.py: the
                                                                                 standard leaves it open
9   a low-level FAP that has a value (sent, or copied by rule 3, now or    M     facts §4 (semantics
    earlier) overrides the value FAP 1/2 give it                                 of FAP 1/2 are [M])
10  viseme_def, init_face, expression_def change nothing shown             M     facts §4.1, §4.2
11  no clamping: a decoder shows what was sent                             S     README (the codec
                                                                                 decodes what was sent)
12  FAPU = key distance on the neutral face / 1024 (``spec/fapu.csv``)     S     facts §1
13  IRISD0 from the right eye (3.2 - 3.4) when 3.1/3.3 are missing         S     facts §1 ("= 3.2.y -
                                                                                 3.4.y")
14  AU = 1e-5 rad, not measured                                            S     facts §1
15  translational FAP: its feature point moves value x FAPU along the      S     facts §1, §2 table
    FAP's direction; FAPs on one point add up
16  axes: +x the face's left, +y up, +z forward (out of the face)          S     facts "Terminology"
17  dilate_l/r_pupil (29/30, "growing"): the pupil grows, its centre       S     facts §2 (IRISD,
    3.5/3.6 does not move                                                        "Dilation of pupil")
18  eyeball rotations 23-26: centre not given; points not moved            M     facts §2 note [M]
19  head rotations 48-50 turn every feature point rigidly about 7.1 (top   S     facts §2, §3 (7.1
    of spine), right-handed about +x (pitch), +y (yaw), +z (roll): the           "center of head
    sense that moves a point in front of 7.1 (above it, for roll) toward         rotation"); the sense
    the FAP's direction word (down, left, right)                                 from spec/faps.csv
20  tongue_roll 47 (6.3/6.4, "concave upward"): no centre; not moved       M     facts §2
21  the suite checks only a driven point's component along the FAP's      S     the suite's choice: the
    direction, when no other FAP acts (:func:`checkable`); under a lone          table fixes no more
    head rotation, every component of every point
22  several head rotations at once: roll, then pitch, then yaw; the head   M     not given by any source
    turns after the face has moved (local FAPs in the head's frame)              (never checked)
==  =====================================================================  ====  ========================

Real decoders realise some FAPs as motions the table does not spell out (open_jaw as a rotation
of the jaw that drops 2.1 by value x MNS, eyelids on an arc over the eyeball): the component
along the FAP's direction is what rule 15 pins down; the others are the decoder's. A head
rotation is different: the whole head turns about a point the FDP gives (7.1), so a lone one
pins every point (rule 19). The eyeballs' centres are not feature points (3.5/3.6 are on the
pupils) and the tongue has no axis in the tables, so those rotations are left unchecked (18, 20).
"""
from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.reference_fapu import fapu_from_points, fapu_units
from mpeg4fa.spec import (
    EXPRESSION_PROFILES, EXPRESSIONS, FAP_GROUP, FAP_PARTNERS, FAPS, FULL_INTENSITY, N_FAP_GROUPS, N_FAPS,
    VISEME_PROFILES, VISEMES,
)

__all__ = ["RULES", "weakest", "shown_values", "checkable", "fapu_from_points", "fapu_units", "feature_point_positions", "rotations",
           "head_orientation", "HEAD_CENTRE", "feature_point_tolerance", "TOLERANCE", "DIRECTIONS", "INTERPOLATE"]

RULES: dict[int, tuple[str, str]] = {
    1: ("a FAP never sent shows 0", "S"),
    2: ("an unsent FAP keeps its previous value", "M"),
    3: ("mask type 2 copies the left/right, else inner/outer counterpart sent in the frame", "M"),
    4: ("FAP 1 and FAP 2 hold like the others", "M"),
    5: ("viseme = v1 * blend/63 + v2 * (1 - blend/63)", "S"),
    6: ("expression = e1 * i1/63 + e2 * i2/63", "M"),
    7: ("blend/intensity above 63 count as 63", "S"),
    8: ("viseme/expression FAP values are the spec/ profiles", "M"),
    9: ("a low-level FAP with a value overrides FAP 1/2", "M"),
    10: ("viseme_def, init_face, expression_def change nothing shown", "M"),
    11: ("no clamping", "S"),
    12: ("FAPU = key distance / 1024 (spec/fapu.csv)", "S"),
    13: ("IRISD0 from the right eye when the left is missing", "S"),
    14: ("AU = 1e-5 rad", "S"),
    15: ("a translational FAP moves its point value x FAPU along its direction; FAPs add", "S"),
    16: ("axes: +x the face's left, +y up, +z forward", "S"),
    17: ("pupil dilation moves no point", "S"),
    18: ("eyeball rotations move no point here (no centre given)", "M"),
    19: ("head rotations turn every point rigidly about 7.1, right-handed, sense from the direction word", "S"),
    20: ("tongue_roll moves no point here (no centre given)", "M"),
    21: ("only the driven point's component along the FAP's direction is checked; a lone head rotation: all", "S"),
    22: ("several head rotations: roll, pitch, yaw; after the local FAPs", "M"),
}
"""Rule number -> (short text, confidence V/S/M), as in the module docstring's table."""


def weakest(rules: Iterable[int]) -> str:
    """The confidence of a result that rests on all of ``rules``: the weakest of theirs (V > S > M)."""
    order = "VSM"
    found = [RULES[r][1] for r in rules]
    return max(found, key=order.index) if found else "V"


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
"""Unit vector of each direction word of ``spec/faps.csv`` that moves a point (rule 16). The others
(``growing``: pupil dilation; ``concave upward``: tongue roll) move no point (rules 17, 20)."""

_GROUP_INDEX = tuple(int(g) - 1 for g in FAP_GROUP)
"""0-based FAP group of each column."""
_PARTNERS = tuple(tuple(int(p) for p in row if p >= 0) for row in FAP_PARTNERS)
"""Each column's counterparts in the order rule 3 tries them (left/right, then inner/outer)."""
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
    """The 68 values FAP 1 plus FAP 2 stand for (rules 5-8, 10)."""
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
    bad = ~np.isin(group_types, (0, 1, 2, 3))
    if bad.any():
        k, g = (int(x) for x in np.argwhere(bad)[0])
        raise ConformanceError(f"group {g + 1} mask type {group_types[k, g]} is not 0..3", where=f"frame {k}")
    out = np.zeros((n, N_FAPS), dtype=np.float64)
    current = [0.0] * N_FAPS       # each FAP's value so far (rule 1: 0 before)
    has_value = [False] * N_FAPS   # sent or copied at some frame so far (rule 9)
    vis = (0, 0, 0, 0)             # FAP 1 fields last sent (rule 4)
    exp = (0, 0, 0, 0, 0, 0)       # FAP 2 fields last sent
    high_of: dict[tuple, np.ndarray] = {}
    for k in range(n):
        sent, row, types = mask[k].tolist(), values[k].tolist(), group_types[k].tolist()
        for col in range(2, N_FAPS):
            if sent[col]:
                current[col], has_value[col] = float(row[col]), True
                continue
            if types[_GROUP_INDEX[col]] != INTERPOLATE:
                continue  # rule 2: hold
            for partner in _PARTNERS[col]:  # left/right first, then inner/outer; sent ones only (rule 3)
                if sent[partner]:
                    current[col], has_value[col] = float(row[partner]), True
                    break
        if sent[0]:
            vis = tuple(int(x) for x in viseme[k])
        if sent[1]:
            exp = tuple(int(x) for x in expression[k])
        if (vis, exp) not in high_of:
            high_of[(vis, exp)] = _high_level(np.array(vis), np.array(exp), k)
        high = high_of[(vis, exp)]
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
    """(column, feature point, direction) of every FAP that moves a point (rules 15-17)."""
    rows = []
    for k, record in enumerate(FAPS):
        if record.fapu is None or record.fapu == "AU" or record.direction not in DIRECTIONS:
            continue
        for label in record.feature_point:
            rows.append((k, label, np.array(DIRECTIONS[record.direction])))
    return tuple(rows)


_MOVES = _translational()

HEAD_CENTRE = "7.1"
"""The feature point head rotations turn about (rule 19: "top of spine, center of head rotation")."""
_HEAD_AXES = {"pitch": 0, "yaw": 1, "roll": 2}
"""Head rotation FAPs by the word their name carries (head_pitch, ...) -> the coordinate axis they turn about."""
_PROBE = {0: (0.0, 0.0, 1.0), 1: (0.0, 0.0, 1.0), 2: (0.0, 1.0, 0.0)}
"""A point in front of the centre (pitch, yaw) or above it (roll): where the direction word is read."""


def _head_rotations() -> tuple[tuple[int, int, float], ...]:
    """(column, axis, sense) of FAPs 48-50, in the order rule 22 applies them (roll, pitch, yaw).

    The sense is +1 when a right-handed turn about +axis moves the probe point toward the FAP's
    direction word (its velocity is axis x probe), else -1: read off ``spec/faps.csv``, not assumed.
    """
    rows = []
    for k, record in enumerate(FAPS):
        word = record.name.split("_")[-1]
        if record.fapu != "AU" or not record.name.startswith("head_") or word not in _HEAD_AXES:
            continue
        axis = _HEAD_AXES[word]
        velocity = np.cross(np.eye(3)[axis], _PROBE[axis])
        rows.append((k, axis, 1.0 if float(velocity @ np.array(DIRECTIONS[record.direction])) > 0 else -1.0))
    order = {2: 0, 0: 1, 1: 2}
    return tuple(sorted(rows, key=lambda row: order[row[1]]))


_HEAD = _head_rotations()
assert len(_HEAD) == 3, "spec/faps.csv must name head_pitch, head_yaw and head_roll"
_HEAD_COLUMNS = frozenset(col for col, _, _ in _HEAD)


def _turn(axis: int, angle: float) -> np.ndarray:
    """Right-handed rotation matrix by ``angle`` radians about coordinate ``axis``."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = ((1, 2), (2, 0), (0, 1))[axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def head_orientation(angles: Mapping[int, float]) -> np.ndarray:
    """The head's rotation matrix for head FAP angles in radians, keyed by FAP number (rules 19, 22)."""
    m = np.eye(3)
    for col, axis, sense in _HEAD:
        m = _turn(axis, sense * float(angles.get(col + 1, 0.0))) @ m
    return m


def feature_point_positions(neutral: Mapping[str, np.ndarray], shown: np.ndarray) -> dict[str, np.ndarray]:
    """Expected ``(n, 3)`` position per frame of every FAP-driven feature point the face has.

    ``neutral`` maps labels to neutral positions (FDP coordinates), ``shown`` is
    :func:`shown_values`' output. A point moves by value x FAPU unit along each translational
    FAP's direction that drives it (rule 15); then, when a head rotation is sent, every point
    turns with the head about 7.1 (rules 19, 22), so every point is driven. Points the face lacks
    are absent; FAPs whose FAPU cannot be measured on this face are skipped; eyeball and tongue
    rotations move nothing here (rules 18, 20).
    """
    shown = np.asarray(shown, dtype=np.float64)
    if shown.ndim != 2 or shown.shape[1] != N_FAPS:
        raise ConformanceError(f"shown must be (n, {N_FAPS}), got {shown.shape}")
    units = fapu_units(fapu_from_points(neutral))
    turning = HEAD_CENTRE in neutral and bool(np.any(shown[:, sorted(_HEAD_COLUMNS)]))
    result: dict[str, np.ndarray] = {}

    def track(label: str) -> np.ndarray:
        if label not in result:
            start = np.asarray(neutral[label], dtype=np.float64).reshape(3)
            result[label] = np.repeat(start[None, :], len(shown), axis=0)
        return result[label]

    for col, label, direction in _MOVES:
        if label in neutral and np.isfinite(units[col]):
            track(label)[:] += (shown[:, col] * units[col])[:, None] * direction[None, :]  # every frame at once
    if turning:
        for label in neutral:
            track(label)
        centre = np.asarray(neutral[HEAD_CENTRE], dtype=np.float64).reshape(3)
        for k in range(len(shown)):
            angles = {col + 1: shown[k, col] * units[col] for col in _HEAD_COLUMNS}
            if any(angles.values()):
                turn = head_orientation(angles)
                for track_k in result.values():
                    track_k[k] = centre + turn @ (track_k[k] - centre)
    return result


def checkable(neutral: Mapping[str, np.ndarray], shown: np.ndarray) -> dict[str, np.ndarray]:
    """Which components of :func:`feature_point_positions` the standard pins down: ``(n, 3)`` bool per point.

    A component (x, y or z) of a point is checkable in a frame when every FAP that is non-zero in
    it is a translational FAP that drives this point along that axis (rule 15): the single-FAP
    streams of the semantics group. Under a head rotation that is the only non-zero FAP, every
    component of every point is (rule 21). Everything else is a decoder's own realisation, which
    the table does not fix: how a jaw carries the lips, an eyelid's arc over the eyeball (its z),
    skin following a moved point, and every point under an eyeball or tongue rotation.
    """
    shown = np.asarray(shown, dtype=np.float64)
    positions = feature_point_positions(neutral, shown)
    units = fapu_units(fapu_from_points(neutral))
    axis_of = {}  # column -> (label, axis) for the FAPs whose FAPU this face has
    for col, label, direction in _MOVES:
        if np.isfinite(units[col]):
            axis_of.setdefault(col, set()).add((label, int(np.flatnonzero(direction)[0])))
    result = {label: np.zeros((len(shown), 3), dtype=bool) for label in positions}
    for k in range(len(shown)):
        active = [col for col in range(2, N_FAPS) if shown[k, col] != 0]
        if len(active) == 1 and active[0] in _HEAD_COLUMNS and HEAD_CENTRE in neutral:
            for label in result:
                result[label][k] = True
            continue
        if not active or any(col not in axis_of for col in active):
            continue  # nothing moves, or a rotation, a pupil or an unmeasurable FAP is in play
        for label in result:
            axes = set()
            for col in active:
                here = {axis for lab, axis in axis_of[col] if lab == label}
                if not here:
                    axes = set()
                    break
                axes |= here
            if len(axes) == 1:
                result[label][k, axes.pop()] = True
    return result


def rotations(shown: np.ndarray) -> dict[int, np.ndarray]:
    """Angle in radians per frame ``(n,)`` of every rotational (AU) FAP, keyed by FAP number."""
    shown = np.asarray(shown, dtype=np.float64)
    if shown.ndim != 2 or shown.shape[1] != N_FAPS:
        raise ConformanceError(f"shown must be (n, {N_FAPS}), got {shown.shape}")
    units = fapu_units({})
    return {record.number: shown[:, k] * units[k] for k, record in enumerate(FAPS) if record.fapu == "AU"}
