"""Head pose from tracked points: a rigid fit to the neutral face, and its pitch, yaw and roll.

Why a fit and not a landmark model's own pose: the FAPs are displacements on the face, so
the head's motion must first be taken out of every point, in the same frame the neutral
was measured in. The similarity (scale, rotation, translation) that best maps the neutral
face's rigid points (eye corners, nose, forehead: no FAP we send moves them) onto this
frame's gives both the head rotation (FAPs 48-50) and, inverted, the frame's points in the
neutral face's coordinates, where what is left is the face's own motion.

Axes are the MPEG-4 ones (x to the face's left, y up, z out of the face; see
:mod:`mpeg4fa.face.motion`), and the angles are those :func:`mpeg4fa.face.motion.head_rotation`
composes (roll, then pitch, then yaw), so a decoder turning the head by them reproduces the fit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HeadPose:
    """``points = scale * rotation @ neutral + translation`` (row vectors: ``p @ rotation.T``)."""

    scale: float
    rotation: np.ndarray     # (3, 3)
    translation: np.ndarray  # (3,)
    rms: float               # residual of the rigid points, in the points' units

    def to_neutral(self, points: np.ndarray) -> np.ndarray:
        """Points of this frame ``(..., 3)`` in the neutral face's coordinates (head motion removed)."""
        return (np.asarray(points, dtype=np.float64) - self.translation) @ self.rotation / self.scale

    def angles(self) -> tuple[float, float, float]:
        """(pitch, yaw, roll) in radians, as :func:`mpeg4fa.face.motion.head_rotation` composes them."""
        return rotation_angles(self.rotation)


IDENTITY = HeadPose(1.0, np.eye(3), np.zeros(3), 0.0)


def fit_similarity(neutral: np.ndarray, points: np.ndarray) -> HeadPose:
    """The least-squares similarity mapping ``neutral`` ``(n, 3)`` onto ``points`` ``(n, 3)`` (Umeyama 1991).

    Rows with a NaN in either are left out; fewer than three usable rows give the identity."""
    a = np.asarray(neutral, dtype=np.float64)
    b = np.asarray(points, dtype=np.float64)
    ok = np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1)
    a, b = a[ok], b[ok]
    if len(a) < 3:
        return IDENTITY
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    da, db = a - ca, b - cb
    var_a = float((da ** 2).sum()) / len(a)
    if var_a <= 0:
        return IDENTITY
    cov = db.T @ da / len(a)
    u, s, vt = np.linalg.svd(cov)
    d = np.ones(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        d[2] = -1.0
    rotation = u @ np.diag(d) @ vt
    scale = float((s * d).sum() / var_a)
    translation = cb - scale * rotation @ ca
    residual = b - (scale * a @ rotation.T + translation)
    return HeadPose(scale, rotation, translation, float(np.sqrt((residual ** 2).sum(axis=1).mean())))


def rotation_angles(rotation: np.ndarray) -> tuple[float, float, float]:
    """(pitch, yaw, roll) of ``R = Ry(yaw) @ Rx(pitch) @ Rz(roll)``: row 1 of R is that of Rx Rz,
    column 2 that of Ry Rx."""
    r = np.asarray(rotation, dtype=np.float64)
    pitch = float(-np.arcsin(np.clip(r[1, 2], -1.0, 1.0)))
    roll = float(np.arctan2(r[1, 0], r[1, 1]))
    yaw = float(np.arctan2(r[0, 2], r[2, 2]))
    return pitch, yaw, roll
