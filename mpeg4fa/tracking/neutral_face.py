"""A face found in a photo made the neutral face an FDP describes (the facts file's neutral face definition, [S]).

A photo is seldom of the neutral face: people smile, talk, blink. The FDP's points are made neutral, their texture
coordinates left where the photo shows them, so a receiver paints the photo's lips and lids onto the neutral ones:

* the inner lip midpoints 2.6-2.9 sit at the receiving head's own share of the way along the photo's contour
  (:func:`_lip_midpoints_slid`);
* the lips touch (item 7, :func:`_lips_in_contact`) and are level, the corners at the height of the line of the lips
  (item 7, :func:`_lips_level`);
* a shut eye opens to the head's own lid opening (item 5, :func:`_eyes_open`).

:func:`make_neutral` applies them in that order and says what it changed (:func:`not_neutral`).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from mpeg4fa.spec.landmark_points import LANDMARK_POINTS
from mpeg4fa.tracking.landmarks import OPENING_RINGS

__all__ = ["make_neutral", "not_neutral", "INNER_LIP_PAIRS", "INNER_LIP_MIDPOINTS"]


def make_neutral(points: dict[str, np.ndarray], pixels: dict[str, np.ndarray], marks3: np.ndarray, marks2: np.ndarray,
                 head: Mapping[str, np.ndarray], given: set[str]) -> list[str]:
    """``points`` (the head's frame, mm) and ``pixels`` of the face found made neutral in place (see the module
    docstring), against ``head``'s own points; ``marks3``/``marks2``: the landmarks in the head's frame and in pixels;
    ``given`` labels (a user's) stay. Returns :func:`not_neutral`'s lines on the face as found."""
    notes = not_neutral(points, head, given)
    _lip_midpoints_slid(points, pixels, marks3, marks2, head, given)
    _lips_in_contact(points, head, given)
    _lips_level(points, head, given)
    _eyes_open(points, head, given)
    return notes


INNER_LIP_MIDPOINTS = {"2.6": ("2.2", "2.4"), "2.7": ("2.2", "2.5"), "2.8": ("2.3", "2.4"), "2.9": ("2.3", "2.5")}
"""The inner lip points the standard places midway along a contour, and the contour's ends."""


def _ring_path(ring: Sequence[int], start: int, end: int) -> list[int]:
    """The landmarks of ``ring`` from ``start`` to ``end`` the shorter way round (both included)."""
    i, j, n = ring.index(start), ring.index(end), len(ring)
    forward = [ring[(i + k) % n] for k in range((j - i) % n + 1)]
    backward = [ring[(i - k) % n] for k in range((i - j) % n + 1)]
    return forward if len(forward) <= len(backward) else backward


def _lip_midpoints_slid(points: dict[str, np.ndarray], pixels: dict[str, np.ndarray], marks3: np.ndarray,
                        marks2: np.ndarray, head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """Each inner lip midpoint (:data:`INNER_LIP_MIDPOINTS`) moved along the photo's own inner lip contour (the
    landmark model's ring, in 3D and in pixels alike) to the share of the way from the midline to the corner, across
    the face, that the receiving head's point has. "Midway" is read differently by the landmark model (its contour's
    middle landmark: 0.50-0.54 of the way on the astronaut) and by the head (half the arc: 0.64 on the upper lip,
    0.45 on the lower), and a calibration that slid the head's upper and lower contours apart, 0.7 mm from each other,
    sheared the lips where they meet: the bilabials' pressed lips showed a notched seal line. Where the point sits on
    its contour is the head's; the contour's shape, and so the lips' shape, stays the photo's."""
    ring = list(OPENING_RINGS["mouth"])
    for label, (middle, corner) in INNER_LIP_MIDPOINTS.items():
        if label in given or label not in points or not {label, middle, corner} <= head.keys():
            continue
        ends = [LANDMARK_POINTS[end].indices for end in (middle, corner)]
        if any(len(e) != 1 or e[0] not in ring for e in ends):
            continue
        path = _ring_path(ring, ends[0][0], ends[1][0])
        x = marks3[path, 0]
        along = np.maximum.accumulate((x - x[0]) / (x[-1] - x[0])) if abs(x[-1] - x[0]) > 1e-9 else None
        if along is None or along[-1] <= along[0]:
            continue
        across = float(head[corner][0] - head[middle][0])
        if abs(across) < 1e-9:  # a head whose corner sits on its midline: no share to take
            continue
        share = float(head[label][0] - head[middle][0]) / across
        k = int(np.clip(np.searchsorted(along, share, side="right") - 1, 0, len(path) - 2))
        t = float(np.clip((share - along[k]) / max(along[k + 1] - along[k], 1e-12), 0.0, 1.0))
        points[label] = marks3[path[k]] + t * (marks3[path[k + 1]] - marks3[path[k]])
        pixels[label] = marks2[path[k]] + t * (marks2[path[k + 1]] - marks2[path[k]])


INNER_LIP_PAIRS = (("2.2", "2.3"), ("2.6", "2.8"), ("2.7", "2.9"))
"""Upper and lower inner lip points that meet in the neutral face."""


def _lips_apart(points: Mapping[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]
                ) -> dict[tuple[str, str], float]:
    """Each inner lip pair (:data:`INNER_LIP_PAIRS`) found, not given: how much further apart (mm, y) it is than the
    head's own pair (0 or less: in contact as the head models it)."""
    return {(u, lo): float(points[u][1] - points[lo][1]) - max(float(head[u][1] - head[lo][1]), 0.0)
            for u, lo in INNER_LIP_PAIRS if {u, lo} <= points.keys() and {u, lo} <= head.keys() and not {u, lo} & given}


def _lips_in_contact(points: dict[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """An FDP describes the neutral face, whose lips are in contact (the facts file's neutral face
    definition, item 7, [S]); a photo of a smile or of speech has them apart, and a head calibrated to
    that gap shows its own teeth through it at rest. Each pair of inner lip points found (not given)
    further apart than the head's own pair closes about its midpoint to the head's gap (the lips' contact
    as the head models it; the points stay distinct). The texture coordinates stay on the photo's lips."""
    for (upper, lower), apart in _lips_apart(points, head, given).items():
        if apart > 0.0:
            points[upper][1] -= apart / 2.0
            points[lower][1] += apart / 2.0


LIP_CORNERS = {"left": ("8.3", "2.4"), "right": ("8.4", "2.5")}
"""The outer and inner lip corners of each side of the face."""
LIP_POINTS = ("2.2", "2.3", "2.4", "2.5", "2.6", "2.7", "2.8", "2.9",
              "8.1", "8.2", "8.3", "8.4", "8.5", "8.6", "8.7", "8.8", "8.9", "8.10")
"""The points of the lips' contours, which a smile bends."""


def _corner_lifts(points: Mapping[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]
                  ) -> dict[tuple[str, str], float]:
    """Each side's lip corners (:data:`LIP_CORNERS`, none given): their mean height (mm) over the line of the lips
    at the midline (inner lips 2.2/2.3) beyond where the head's own corners sit over its own line."""
    if not {"2.2", "2.3"} <= points.keys() or not {"2.2", "2.3"} <= head.keys():
        return {}
    line, head_line = ((p["2.2"][1] + p["2.3"][1]) / 2.0 for p in (points, head))
    out = {}
    for corners in LIP_CORNERS.values():
        seen = [c for c in corners if c in points and c in head]
        if seen and not set(corners) & given:
            out[corners] = float(np.mean([(points[c][1] - line) - (head[c][1] - head_line) for c in seen]))
    return out


def _lips_level(points: dict[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """In the neutral face the line of the lips is horizontal, at the height of the lip corners (the facts
    file's neutral face definition, item 7, [S]); a smiling photo has its corners raised (the astronaut's
    6.6-8.0 mm over the line of her lips), and a head calibrated to them smiles in every expression. Each side's
    corners are brought to the line's height at the midline (:func:`_corner_lifts`: as the head's own corners sit
    against its own line), and the lip points between follow by the square of their share of the way out
    from the midline to the corner, which takes the bend of a smile out of the contours (an upper and lower inner
    lip pair by their mean share, so they stay in contact). Points given (a user's) stay, and a corner given keeps
    its side as found. The texture coordinates stay on the photo's lips, so the receiver paints the photo's lips
    onto the level ones."""
    lifts = _corner_lifts(points, head, given)
    if not lifts:
        return
    middle = (points["2.2"][0] + points["2.3"][0]) / 2.0
    for corners, lift in lifts.items():
        reach = float(np.mean([points[c][0] for c in corners if c in points and c in head])) - middle
        if abs(reach) < 1e-6:
            continue
        share = {label: (points[label][0] - middle) / reach for label in LIP_POINTS if label in points}
        for pair in INNER_LIP_PAIRS:  # a pair moves as one, so the contact _lips_in_contact made stays
            if set(pair) <= share.keys():
                share.update(dict.fromkeys(pair, (share[pair[0]] + share[pair[1]]) / 2.0))
        for label, t in share.items():
            if t > 0.0 and label not in given:
                points[label][1] -= lift * min(t, 1.0) ** 2


EYES = {"left": ("3.1", "3.3", "3.13", "3.9"), "right": ("3.2", "3.4", "3.14", "3.10")}
"""Each eye's upper and lower lid margin at the middle, and the folds above and below them."""
SHUT = 0.5
"""An eye whose lids are less than this share of the head's own opening apart is shut (a blink, a wink)."""


def _shut_eyes(points: Mapping[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]
               ) -> dict[str, tuple[float, float]]:
    """The eyes shut in the photo: side -> (the lids' gap, the head's own), mm."""
    out = {}
    for side, (upper, lower, _, _) in EYES.items():
        if {upper, lower} <= points.keys() and {upper, lower} <= head.keys() and not {upper, lower} & given:
            gap, own = points[upper][1] - points[lower][1], head[upper][1] - head[lower][1]
            if own > 0 and gap < SHUT * own:
                out[side] = (float(gap), float(own))
    return out


def _eyes_open(points: dict[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """In the neutral face the lids are tangent to the iris (the facts file's neutral face definition, item 5,
    [S]): its lid opening is IRISD0, a FAPU every lid motion is measured in. A photo taken in a blink has its lids
    together, and a head calibrated to them had no opening at all (IRISD0 <= 0: no head could be made from the FDP).
    A shut eye (:data:`SHUT`) opens to the head's own opening about the middle of the photo's lids, its folds
    moving with the margins; the texture coordinates stay on the photo's closed lids."""
    for side in _shut_eyes(points, head, given):
        upper, lower, upper_fold, lower_fold = EYES[side]
        middle = (points[upper][1] + points[lower][1]) / 2.0
        head_middle = (head[upper][1] + head[lower][1]) / 2.0
        for margin, fold in ((upper, upper_fold), (lower, lower_fold)):
            move = middle + (head[margin][1] - head_middle) - points[margin][1]
            points[margin][1] += move
            if fold in points and fold not in given:
                points[fold][1] += move


NOTE_MM = 2.0
"""Lips apart, or corners over the line of the lips, by less than this (beyond the head's own) are not worth a
note: the landmark model reads the generic head's own rendered corners up to 1 mm high."""


def not_neutral(points: Mapping[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str] = frozenset()
                ) -> list[str]:
    """One line for each way the face found in a photo (``points``: as found, in the head's frame, mm) is not the
    neutral face, which the FDP is then made (:func:`_lips_in_contact`, :func:`_lips_level`, :func:`_eyes_open`), with
    the figure, so a user knows why the head does not smile, part its lips or shut its eyes as the photo does."""
    out = []
    apart = max(_lips_apart(points, head, given).values(), default=0.0)
    if apart >= NOTE_MM:
        out.append(f"the lips are {apart:.0f} mm apart in the photo; closed in the FDP, as the neutral face's are")
    lifts = _corner_lifts(points, head, given)
    lift = float(np.mean(list(lifts.values()))) if lifts else 0.0
    if abs(lift) >= NOTE_MM:
        way = "over" if lift > 0 else "under"
        out.append(f"the lip corners sit {abs(lift):.0f} mm {way} the line of the lips in the photo "
                   f"({'a smile' if lift > 0 else 'turned down'}); level in the FDP, as the neutral face's are")
    for side, (gap, own) in _shut_eyes(points, head, given).items():
        out.append(f"the {side} eye is shut in the photo (its lids {max(gap, 0.0):.1f} mm apart); opened in the FDP "
                   f"as wide as the head's own ({own:.1f} mm), as the neutral face's eyes are")
    return out
