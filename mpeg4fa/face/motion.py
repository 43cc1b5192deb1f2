"""Layer 2 of the animation: what each low-level FAP does to its feature point.

The spec tables say, for FAPs 3-68, which feature point moves, in which FAPU and
in which direction. This module turns them into the engine's vocabulary:

* ``translate``: the point moves by value x FAPU along the direction (most FAPs);
* ``jaw``: FAPs 3 (open: a rotation about the jaw pivot solved so that 2.1 drops
  by exactly value x MNS), 14 (thrust) and 15 (shift) move the jaw region;
* ``lid``: FAPs 19-22 move the eyelid point by value x IRISD vertically, on an arc
  about the eyeball centre so that the lid slides over the eye;
* ``eye``: 23-26 rotate an eyeball (value x AU), 27/28 push it forward;
* ``pupil``: 29/30 change the pupil diameter (a renderer parameter, no motion);
* ``tongue_roll``: 47 rolls the tongue borders 6.3/6.4 up about its long axis;
* ``head``: 48-50 rotate the head about 7.1 (pitch, yaw, roll).

Directions are the MPEG-4 axes: x to the face's left, y up, z out of the face.
Positive rotations follow the right-hand rule about +x (pitch: face down),
+y (yaw: face turns to its left) and +z (roll: head tilts to its right).
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.spec import ANGLE_UNIT as ANGLE_UNIT_RAD  # noqa: F401  (part of this module's vocabulary)
from mpeg4fa.spec import FAP_BY_NAME, FAPS, N_FAPS

DIRECTION = {
    "down": (0.0, -1.0, 0.0), "up": (0.0, 1.0, 0.0),
    "left": (1.0, 0.0, 0.0), "right": (-1.0, 0.0, 0.0), "forward": (0.0, 0.0, 1.0),
}


def _numbers(table: dict[str, object]) -> dict[int, object]:
    """The same table keyed by FAP number (the names are those of ``spec/faps.csv``)."""
    return {FAP_BY_NAME[name].number: value for name, value in table.items()}


JAW = _numbers({"open_jaw": "open", "thrust_jaw": "thrust", "shift_jaw": "shift"})
LIDS = _numbers({"close_t_l_eyelid": "eye_l", "close_t_r_eyelid": "eye_r",
                 "close_b_l_eyelid": "eye_l", "close_b_r_eyelid": "eye_r"})
EYE_ROTATION = _numbers({"yaw_l_eyeball": ("eye_l", "yaw"), "yaw_r_eyeball": ("eye_r", "yaw"),
                         "pitch_l_eyeball": ("eye_l", "pitch"), "pitch_r_eyeball": ("eye_r", "pitch")})
EYE_THRUST = _numbers({"thrust_l_eyeball": "eye_l", "thrust_r_eyeball": "eye_r"})
PUPIL = _numbers({"dilate_l_pupil": "eye_l", "dilate_r_pupil": "eye_r"})
TONGUE_ROLL = FAP_BY_NAME["tongue_roll"].number
HEAD = _numbers({"head_pitch": "pitch", "head_yaw": "yaw", "head_roll": "roll"})
AXIS_OF = {"pitch": 0, "yaw": 1, "roll": 2}


def kind(fap: int) -> str:
    """How the engine realises FAP ``fap`` (3..68)."""
    if fap in JAW:
        return "jaw"
    if fap in LIDS:
        return "lid"
    if fap in EYE_ROTATION or fap in EYE_THRUST:
        return "eye"
    if fap in PUPIL:
        return "pupil"
    if fap == TONGUE_ROLL:
        return "tongue_roll"
    if fap in HEAD:
        return "head"
    return "translate"


def direction(fap: int) -> np.ndarray:
    """Unit vector of a FAP's positive direction (translational and lid/jaw FAPs)."""
    word = FAPS[fap - 1].direction
    if word not in DIRECTION:
        raise FaceError(f"FAP {fap} ({FAPS[fap - 1].name}) has no translational direction ({word})")
    return np.array(DIRECTION[word])


def rotation_matrix(axis: int, angle: float) -> np.ndarray:
    """Right-handed rotation by ``angle`` radians about coordinate axis 0, 1 or 2."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def head_rotation(pitch: float, yaw: float, roll: float) -> np.ndarray:
    """Head orientation: roll, then pitch, then yaw (angles in radians)."""
    return rotation_matrix(1, yaw) @ rotation_matrix(0, pitch) @ rotation_matrix(2, roll)


def arc_angle(offset: np.ndarray, drop: float) -> float:
    """Angle about +x that lowers a point at ``offset`` (y, z from the pivot) by ``drop``.

    Solves y cos(a) - z sin(a) = y - drop, the branch nearest zero; a drop beyond
    what the arc can reach is clamped to the arc's lowest (or highest) point.
    """
    y, z = float(offset[0]), float(offset[1])
    radius = float(np.hypot(y, z))
    if radius == 0.0 or drop == 0.0:
        return 0.0
    # y cos a - z sin a = R cos(a + phase): take the root closest to a = 0
    phase = np.arctan2(z, y)
    base = np.arccos(np.clip((y - drop) / radius, -1.0, 1.0))
    roots = (np.array([base - phase, -base - phase]) + np.pi) % (2 * np.pi) - np.pi
    return float(roots[np.argmin(np.abs(roots))])
