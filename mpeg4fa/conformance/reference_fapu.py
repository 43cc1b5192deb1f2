"""FAPU measured on a neutral face, for the suite's reference model (independent of ``mpeg4fa.face``).

A conformance suite that borrowed the face engine's FAPU code could not catch a wrong FAPU
definition in it, so this module measures them again from the definitions in ``spec/fapu.csv``
(facts file §1): each distance is ``point_a.axis - point_b.axis`` on the neutral face and one
unit is that distance / 1024; AU is a fixed angle (1e-5 rad), not measured.
"""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.spec import ANGLE_UNIT, FAPS, FAPU, FAPU_NAMES, FEATURE_POINT_MIRROR, N_FAPS

__all__ = ["fapu_from_points", "fapu_units", "fapu_symbol_key"]

_AXIS = {"x": 0, "y": 1, "z": 2}
_MEASURED = tuple(f for f in FAPU.values() if f.distance)
"""The five measured FAPU records (IRISD, ES, ENS, MNS, MW), in ``FAPU_NAMES`` order."""
assert tuple(f.distance for f in _MEASURED) == FAPU_NAMES


def fapu_symbol_key(symbol: str) -> str | None:
    """Key of :func:`fapu_from_points`' result for a FAP's FAPU symbol (``"MNS"`` -> ``"MNS0"``);
    None for the angle unit AU."""
    record = FAPU[symbol]
    return record.distance or None


def _pair(points: Mapping[str, np.ndarray], a: str, b: str) -> tuple[np.ndarray, np.ndarray] | None:
    """Both points of a definition, or their left/right mirrors when one of them is missing.

    IRISD0 is defined on the left eye (3.1, 3.3); the facts file says the right eye (3.2, 3.4)
    gives the same distance, so a face that has only the right eye's points is still measured.
    """
    if a in points and b in points:
        return np.asarray(points[a], dtype=np.float64), np.asarray(points[b], dtype=np.float64)
    ma, mb = FEATURE_POINT_MIRROR.get(a), FEATURE_POINT_MIRROR.get(b)
    if ma and mb and ma in points and mb in points:
        return np.asarray(points[ma], dtype=np.float64), np.asarray(points[mb], dtype=np.float64)
    return None


def fapu_from_points(points: Mapping[str, np.ndarray]) -> dict[str, float]:
    """One unit of each measurable FAPU (distance0 / 1024), keyed by ``FAPU_NAMES`` (``"MNS0"``...).

    ``points`` maps feature point labels to neutral-face positions (x to the face's left, y up,
    z forward). A FAPU whose points are missing is left out of the result (a subset face);
    a distance that is not positive means the face's axes are wrong and is refused.
    """
    units: dict[str, float] = {}
    for record in _MEASURED:
        pair = _pair(points, record.point_a, record.point_b)
        if pair is None:
            continue
        a, b = pair
        axis = _AXIS[record.axis]
        distance = float(a[axis] - b[axis])
        if not np.isfinite(distance) or distance <= 0.0:
            raise ConformanceError(
                f"{record.distance} = {record.definition.split('=', 1)[-1].strip()} = {distance!r} is not positive",
                hint="feature points must use x toward the face's left and y up (facts file, axes)")
        units[record.distance] = distance / record.divisor
    return units


def fapu_units(fapu: Mapping[str, float]) -> np.ndarray:
    """``(68,)`` length (or angle, radians) of one unit of each FAP: its FAPU's unit from ``fapu``
    (as :func:`fapu_from_points` returns it), ``ANGLE_UNIT`` for AU FAPs, 0 for FAP 1/2 (no FAPU);
    NaN where the FAPU is not in ``fapu`` (cannot be measured on this face)."""
    out = np.zeros(N_FAPS, dtype=np.float64)
    for k, record in enumerate(FAPS):
        if record.fapu is None:
            continue
        key = fapu_symbol_key(record.fapu)
        out[k] = ANGLE_UNIT if key is None else float(fapu.get(key, np.nan))
    return out
