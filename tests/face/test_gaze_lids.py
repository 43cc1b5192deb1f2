"""Lids that ride on the eye's pitch (issue 29 item 4; mpeg4fa.face.lids.lid_drops), on every exact deformer.

The upper lid point turns about the eye centre with the eyeball's pitch (FAPs 25/26) by its share in
:data:`~mpeg4fa.face.lids.FOLLOW`, the lower one by less; a blink still shuts the eye in any gaze (the
closed upper lid lies on the lower one wherever that one now is); the upper lid never goes below the
lower one, and no lid vertex enters the eyeball. What the viewer sees (iris share, sclera above the
iris) is measured in ``tests/render/test_gaze_lid_pixels.py``.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face.lids import FOLLOW, KNEE, LIDS, SLIT
from mpeg4fa.spec import ANGLE_UNIT, FAPS

from test_lids import closing_value

PITCH = {"eye_l": 25, "eye_r": 26}
FULL = FAPS[24].i_max * FAPS[24].quant_step  # the full I range of FAPs 25/26 (AU)


@pytest.fixture
def face(deformed_face):
    return deformed_face


def _au(degrees: float) -> float:
    return float(np.radians(degrees) / ANGLE_UNIT)


def _angle(face, pose, fap: int) -> float:
    """Elevation (rad, + up) of a lid point about its eye centre, in the y/z plane."""
    _, joint, point, *_ = LIDS[fap]
    off = pose.feature_points[face.mesh.fp_index(point)] - face.mesh.joint(joint)
    return float(np.arctan2(off[1], off[2]))


def _gaze(degrees: float) -> dict[int, float]:
    return {25: _au(degrees), 26: _au(degrees)}


@pytest.mark.parametrize("degrees", [-12.0, -5.0, 5.0, 12.0, 20.0])
def test_lid_points_turn_with_the_eye(face, degrees):
    """Within the linear part of the follow (KNEE of the limit) each lid point turns by its share of the pitch."""
    rest, posed = face.neutral(), face.deform(_gaze(degrees))
    for fap, (_, _, _, _, _, _, side) in LIDS.items():
        share, up, down = FOLLOW[side]
        if abs(share * degrees) > KNEE * (down if degrees > 0 else up):
            continue
        turned = np.degrees(_angle(face, rest, fap) - _angle(face, posed, fap))  # + down
        assert turned == pytest.approx(share * degrees, abs=1e-6), (fap, degrees)


def test_the_follow_eases_into_its_limit(face):
    """Past the knee the upper lid turns less than the eye, never past its limit, and keeps turning the same way."""
    turned = []
    for degrees in np.linspace(-66, 66, 23):
        pose = face.deform(_gaze(degrees))
        turned.append(np.degrees(_angle(face, face.neutral(), 19) - _angle(face, pose, 19)))
    turned = np.array(turned)
    _, up, down = FOLLOW["upper"]
    assert np.all(np.diff(turned) > 0)
    assert turned.max() <= down + 1e-9 and turned.min() >= -up - 1e-9


@pytest.mark.parametrize("fraction", [-1.0, -0.5, -0.3, 0.3, 0.5, 1.0])
def test_a_blink_shuts_the_eye_in_any_gaze(face, fraction):
    """At the closing value the upper lid point lies on the lower one, wherever the gaze has put that one."""
    for eye, pitch in PITCH.items():
        upper = next(f for f, row in LIDS.items() if row[0] == eye and row[6] == "upper")
        lower = next(f for f, row in LIDS.items() if row[0] == eye and row[6] == "lower")
        pose = face.deform({pitch: fraction * FULL, upper: closing_value(face, upper)})
        up_y = pose.feature_points[face.mesh.fp_index(LIDS[upper][2]), 1]
        low_y = pose.feature_points[face.mesh.fp_index(LIDS[lower][2]), 1]
        assert up_y == pytest.approx(low_y, abs=1e-9), (eye, fraction)


def test_a_gaze_alone_never_shuts_the_eye(face):
    """Far down the upper lid follows the eye toward the lower one, but stops a slit short of it."""
    for fraction in np.linspace(-1, 1, 17):
        pose = face.deform({25: fraction * FULL, 26: fraction * FULL})
        for eye in PITCH:
            upper = next(row[2] for row in LIDS.values() if row[0] == eye and row[6] == "upper")
            lower = next(row[2] for row in LIDS.values() if row[0] == eye and row[6] == "lower")
            opening = face.mesh.fp(upper)[1] - face.mesh.fp(lower)[1]
            gap = pose.feature_points[face.mesh.fp_index(upper), 1] - pose.feature_points[face.mesh.fp_index(lower), 1]
            assert gap >= SLIT * opening - 1e-9, (eye, fraction, gap / opening)


def test_no_lid_vertex_enters_the_eyeball_in_any_gaze(face):
    mesh = face.mesh
    for fraction in np.linspace(-1, 1, 9):
        for blink in (0.0, 0.5, 1.0):
            pose = face.deform({25: fraction * FULL, 26: fraction * FULL,
                                19: blink * closing_value(face, 19), 20: blink * closing_value(face, 20)})
            for fap, (eye, joint, *_) in LIDS.items():
                centre = mesh.joint(joint)
                radius = np.linalg.norm(mesh.vertices[mesh.part(eye)] - centre, axis=1).max()
                sheet = pose.vertices[face.rig.lids[fap].rows]
                assert np.linalg.norm(sheet - centre, axis=1).min() > radius, (fap, fraction, blink)


def test_straight_gaze_leaves_the_lids_to_their_faps(face):
    """No pitch, no follow: the lid FAPs alone (and a yaw) move the lid points as before."""
    for fap in LIDS:
        point = LIDS[fap][2]
        sign = -1.0 if LIDS[fap][6] == "upper" else 1.0
        moved = face.deform({fap: 300.0, 23: _au(30), 24: _au(30)}).feature_points[face.mesh.fp_index(point)]
        assert moved[1] - face.mesh.fp(point)[1] == pytest.approx(sign * 300.0 * face.fapu.unit("IRISD"), abs=1e-9)
