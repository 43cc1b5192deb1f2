"""The rigid parts of the face's motion as glTF node animation: the head turn and the eyeballs' turns.

Why nodes, not morph targets: a turn is a rotation, which blended shapes only fake along a
chord; glTF interpolates node rotations spherically. The angles and pivots are the
deformer's own (:func:`mpeg4fa.face.motion.head_rotation` about feature point 7.1; each
eyeball turned by yaw then pitch about its joint, pushed along its thrust FAP), so a
consumer's scene graph turns the parts as the feature-point layer does. Quaternions are
(x, y, z, w), each on the side of the one before so interpolation takes the short way.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from mpeg4fa.face import motion
from mpeg4fa.face.deformers.feature_points import EYE_JOINT  # the deformer's eye pivots
from mpeg4fa.face.model import FaceModel

HEAD_CENTRE = "7.1"
"""The feature point the head turns about (the rig's ``head_fp``)."""
EYES = tuple(EYE_JOINT)
_HEAD_ORDER = {"pitch": 0, "yaw": 1, "roll": 2}


@dataclass(frozen=True)
class Turns:
    """A part's rigid motion over the key frames, about ``centre`` (mm)."""

    centre: np.ndarray            # (3,) mm
    rotations: np.ndarray | None  # (n, 4) unit quaternions, or None: never turns
    offsets: np.ndarray | None    # (n, 3) mm moved after turning (an eyeball's thrust), or None: never


def continuous(quats: np.ndarray) -> np.ndarray:
    """Unit quaternions, each flipped to the side of the one before (the same rotations)."""
    signs = np.sign(np.einsum("ij,ij->i", quats[1:], quats[:-1]) + 1e-12)
    out = quats * np.cumprod(np.r_[1.0, signs])[:, None]
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def head_turns(face: FaceModel, values: np.ndarray) -> Turns | None:
    """FAPs 48-50 at each frame (n, 68 resolved values); None when the head never turns."""
    columns = [number - 1 for number, kind in sorted(motion.HEAD.items(), key=lambda item: _HEAD_ORDER[item[1]])]
    angles = values[:, columns] * motion.ANGLE_UNIT_RAD  # pitch, yaw, roll
    if not np.any(angles):
        return None
    quats = Rotation.from_matrix(np.stack([motion.head_rotation(*row) for row in angles])).as_quat()
    return Turns(centre=face.mesh.fp(HEAD_CENTRE), rotations=continuous(quats), offsets=None)


def eye_turns(face: FaceModel, values: np.ndarray, eye: str) -> Turns:
    """One eyeball's yaw and pitch (FAPs 23-26) and thrust (27, 28) at each frame, about its joint."""
    faps = {kind: number for number, (which, kind) in motion.EYE_ROTATION.items() if which == eye}
    yaw, pitch = (values[:, faps[k] - 1] * motion.ANGLE_UNIT_RAD for k in ("yaw", "pitch"))
    rotations = None
    if np.any(yaw) or np.any(pitch):
        matrices = np.stack([motion.rotation_matrix(1, y) @ motion.rotation_matrix(0, p) for y, p in zip(yaw, pitch)])
        rotations = continuous(Rotation.from_matrix(matrices).as_quat())
    thrust = next(number for number, which in motion.EYE_THRUST.items() if which == eye)
    push = values[:, thrust - 1] * face.fapu.unit("ES")
    offsets = push[:, None] * motion.direction(thrust)[None, :] if np.any(push) else None
    return Turns(centre=face.mesh.joint(EYE_JOINT[eye]), rotations=rotations, offsets=offsets)
