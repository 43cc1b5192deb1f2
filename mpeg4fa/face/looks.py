"""Whether an expression reads at a glance: named measures of a pose against the neutral face.

People judge a talking head by a few motions (the lip corners of a smile, the slant of sad
brows, the raised upper lip and wrinkled nose of disgust). :func:`measures` turns a pose into
those motions in mm (positive in the named sense), :func:`nose_wrinkle` is the wrinkle strength
the renderer draws (0..1, from how far the nose tip is drawn toward the bridge), and
``data/expression_reads.csv`` says, per expression at full intensity, which measures must reach
what (:func:`expression_reads`). Feature points only: every deformer that keeps them exact
measures the same, and a calibrated head is measured on its own points.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np

NOSE_TIP, NOSE_BRIDGE = "9.3", ("9.6", "9.7")
WRINKLE_COMPRESSION = (0.03, 0.10)
"""Shortening of the tip-to-bridge distance where the nose wrinkle starts to show and where it is full."""

GENERIC_FAPU = {"IRISD": 7.83, "ES": 61.554444, "ENS": 51.253889, "MNS": 16.35, "MW": 51.78}
"""The generic head's FAPU (mm): the reads' thresholds are mm on it, scaled by a head's own FAPU."""

_PAIRS = {  # measure -> (points, axis, sign): the mean motion of the points along the axis
    "corner_rise": (("8.3", "8.4"), 1, 1.0),
    "corner_drop": (("8.3", "8.4"), 1, -1.0),
    "cheek_rise": (("5.3", "5.4"), 1, 1.0),
    "lower_lid_rise": (("3.3", "3.4"), 1, 1.0),
    "upper_lid_rise": (("3.1", "3.2"), 1, 1.0),
    "inner_brow_rise": (("4.1", "4.2"), 1, 1.0),
    "brow_drop": (("4.1", "4.2"), 1, -1.0),
    "brow_rise": (("4.1", "4.2", "4.3", "4.4", "4.5", "4.6"), 1, 1.0),
    "upper_lip_rise": (("8.1",), 1, 1.0),
    "jaw_drop": (("2.1",), 1, -1.0),
}
_OUTWARD = {"corner_spread": (("8.3", "8.4"), 1.0), "brow_squeeze": (("4.1", "4.2"), -1.0)}
UNIT = {"corner_rise": "MNS", "corner_drop": "MNS", "cheek_rise": "ENS", "lower_lid_rise": "IRISD",
        "upper_lid_rise": "IRISD", "inner_brow_rise": "ENS", "brow_drop": "ENS", "brow_rise": "ENS",
        "upper_lip_rise": "MNS", "jaw_drop": "MNS", "corner_spread": "MW", "brow_squeeze": "ES",
        "brow_slant": "ENS", "lip_opening": "MNS", "nose_wrinkle": None}
"""The FAPU each measure scales with (the FAPs that make it are in that unit); None: no unit."""


@dataclass(frozen=True)
class Read:
    """One row of ``data/expression_reads.csv``: a measure an expression must reach."""

    expression: str
    measure: str
    minimum: float | None
    maximum: float | None
    why: str

    def holds(self, value: float, scale: float = 1.0) -> bool:
        """Whether ``value`` reaches the read on a head ``scale`` times the generic one (:func:`scale_of`)."""
        return ((self.minimum is None or value >= self.minimum * scale)
                and (self.maximum is None or value <= self.maximum * scale))

    def wanted(self, scale: float = 1.0) -> str:
        parts = ([f">= {self.minimum * scale:.2f}"] if self.minimum is not None else []) + \
                ([f"<= {self.maximum * scale:.2f}"] if self.maximum is not None else [])
        return " and ".join(parts)


def scale_of(measure: str, fapu) -> float:
    """How much larger ``measure``'s motions are on a head with ``fapu`` than on the generic head."""
    unit = UNIT.get(measure)
    return 1.0 if unit is None else float(getattr(fapu, f"{unit}0")) / GENERIC_FAPU[unit]


@lru_cache(maxsize=1)
def expression_reads() -> tuple[Read, ...]:
    """What each expression at full intensity must show (``data/expression_reads.csv``)."""
    with (resources.files("mpeg4fa.face") / "data" / "expression_reads.csv").open(encoding="utf-8") as f:
        return tuple(Read(r["expression"], r["measure"], float(r["min"]) if r["min"] else None,
                          float(r["max"]) if r["max"] else None, r["why"]) for r in csv.DictReader(f))


def nose_wrinkle(neutral: dict[str, np.ndarray], posed: dict[str, np.ndarray]) -> float:
    """0..1: how wrinkled the nose is, from the shortening of the nose tip to bridge distance."""
    if NOSE_TIP not in neutral or not all(label in neutral for label in NOSE_BRIDGE):
        return 0.0

    def length(points):
        bridge = (np.asarray(points[NOSE_BRIDGE[0]]) + np.asarray(points[NOSE_BRIDGE[1]])) / 2
        return float(np.linalg.norm(np.asarray(points[NOSE_TIP]) - bridge))

    rest = length(neutral)
    if rest <= 0:
        return 0.0
    a, b = WRINKLE_COMPRESSION
    t = np.clip(((1.0 - length(posed) / rest) - a) / (b - a), 0.0, 1.0)
    return float(t * t * (3 - 2 * t))


def measures(neutral: dict[str, np.ndarray], posed: dict[str, np.ndarray]) -> dict[str, float]:
    """Every named measure (mm, positive in the named sense; ``nose_wrinkle`` 0..1) of a pose.

    ``neutral`` and ``posed`` map feature point labels to positions in the head's frame
    (x to the face's left, y up, z forward), as :meth:`FaceModel.feature_points` gives."""
    out: dict[str, float] = {}
    for name, (labels, axis, sign) in _PAIRS.items():
        if all(label in neutral for label in labels):
            out[name] = sign * float(np.mean([posed[label][axis] - neutral[label][axis] for label in labels]))
    for name, (labels, sign) in _OUTWARD.items():
        if all(label in neutral for label in labels):
            out[name] = sign * float(np.mean([abs(posed[label][0]) - abs(neutral[label][0]) for label in labels]))
    if all(label in neutral for label in ("4.1", "4.2", "4.5", "4.6")):
        out["brow_slant"] = float(np.mean([(posed[i][1] - neutral[i][1]) - (posed[o][1] - neutral[o][1])
                                           for i, o in (("4.1", "4.5"), ("4.2", "4.6"))]))
    if "2.2" in neutral and "2.3" in neutral:
        out["lip_opening"] = float((posed["2.2"][1] - posed["2.3"][1]) - (neutral["2.2"][1] - neutral["2.3"][1]))
    out["nose_wrinkle"] = nose_wrinkle(neutral, posed)
    return out


def points_of(labels, positions) -> dict[str, np.ndarray]:
    """label -> position, from a pose's ``feature_points`` and the mesh's labels."""
    return dict(zip(labels, np.asarray(positions)))
