"""Facial animation parameter units measured on a neutral face.

Every translational FAP value is a count of FAPU: value x (distance0 / 1024). The
distances are read off the face's own feature points, with the definitions in
``spec/fapu.csv`` (so a tall face and a small face move by the same *fraction*
of their features for the same stream).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.spec import ANGLE_UNIT, FAPU, FAPU_NAMES

_AXIS = {"x": 0, "y": 1, "z": 2}
DISTANCES = tuple(f.symbol for f in FAPU.values() if f.point_a)  # IRISD, ES, ENS, MNS, MW


@dataclass(frozen=True)
class Fapu:
    """The five key distances of a neutral face (model units) plus the fixed angle unit."""

    IRISD0: float
    ES0: float
    ENS0: float
    MNS0: float
    MW0: float

    def unit(self, symbol: str) -> float:
        """Size of one unit of ``symbol`` (``"MNS"``, ``"AU"``...): distance0 / 1024, or radians for AU."""
        if symbol == "AU":
            return ANGLE_UNIT
        record = FAPU.get(symbol)
        if record is None:
            raise FaceError(f"unknown FAPU {symbol!r}", hint=f"one of {', '.join(DISTANCES)}, AU")
        return getattr(self, record.distance) / record.divisor

    def as_dict(self) -> dict[str, float]:
        return {name: float(getattr(self, name)) for name in FAPU_NAMES}


def measure_fapu(points: dict[str, np.ndarray]) -> Fapu:
    """FAPU from feature point positions (label -> xyz), per the standard's definitions."""
    values = {}
    for record in FAPU.values():
        if not record.point_a:
            continue
        try:
            a, b = points[record.point_a], points[record.point_b]
        except KeyError as exc:
            raise FaceError(f"cannot measure {record.distance} without feature point {exc.args[0]}",
                            hint=record.definition) from None
        axis = _AXIS[record.axis]
        values[record.distance] = float(a[axis] - b[axis])
    fapu = Fapu(**values)
    bad = [k for k, v in fapu.as_dict().items() if not v > 0]
    if bad:
        definitions = "; ".join(r.definition for r in FAPU.values() if r.distance in bad)
        shut = ", and a neutral face's eyes open (its lids tangent to the iris)" if "IRISD0" in bad else ""
        raise FaceError(f"non-positive FAPU {', '.join(bad)} (feature points out of order or together)",
                        hint=f"x must point to the face's left and y up{shut}: {definitions}")
    return fapu
