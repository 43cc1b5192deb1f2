"""Eyelids (mpeg4fa.face.lids): sheets of skin turning about the eye centre.

The lid point moves by exactly value x IRISD vertically, the lid never enters the
eyeball, the margin closes onto the opposite margin at the closing value, and
nothing but the lid sheet moves.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face.couplings import PASSIVE_POINTS
from mpeg4fa.face.lids import LIDS, lid_corners

from conftest import EXACT_DEFORMERS, face_under

LID_FAPS = sorted(LIDS)


@pytest.fixture
def face(deformed_face):
    """Each face under each exact deformer: every one keeps the lids' rules."""
    return deformed_face


def closing_value(face, fap: int) -> float:
    """The FAP value that brings the lid point to the height of the opposite lid point."""
    _, _, point, opposite, *_ = LIDS[fap]
    return abs(face.mesh.fp(point)[1] - face.mesh.fp(opposite)[1]) / face.fapu.unit("IRISD")


def _radius(face, pose, eye_joint: str) -> np.ndarray:
    centre = face.mesh.vertices[face.mesh.joints[eye_joint]]
    return np.linalg.norm(pose.part("skin") - centre, axis=1)


@pytest.mark.parametrize("fap", LID_FAPS)
def test_the_lid_point_moves_value_times_irisd(face, fap):
    _, _, point, *_ = LIDS[fap]
    i = face.mesh.fp_index(point)
    sign = -1.0 if LIDS[fap][6] == "upper" else 1.0
    for value in (-200, 100, 512, closing_value(face, fap)):
        moved = face.deform({fap: value}).feature_points[i] - face.mesh.fp(point)
        assert moved[1] == pytest.approx(sign * value * face.fapu.unit("IRISD"), abs=1e-9)
        assert moved[0] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("fap", LID_FAPS)
def test_no_lid_vertex_enters_the_eyeball(face, fap):
    eye, joint = LIDS[fap][:2]
    centre = face.mesh.vertices[face.mesh.joints[joint]]
    eyeball = np.linalg.norm(face.mesh.vertices[face.mesh.part(eye)] - centre, axis=1).max()
    rest = _radius(face, face.neutral(), joint)
    sheet = face.rig.lids[fap].rows - face.mesh.part("skin").start
    assert rest[sheet].min() > eyeball  # the lid starts outside the eyeball ...
    close = closing_value(face, fap)
    for value in np.linspace(-300, 1.2 * close, 9):
        r = _radius(face, face.deform({fap: value}), joint)
        # ... and turning about the centre keeps every vertex at its distance from it
        np.testing.assert_allclose(r, rest, atol=1e-9)


@pytest.mark.parametrize("fap", LID_FAPS)
def test_only_the_lid_sheet_and_its_point_move(face, fap):
    pose = face.deform({fap: 600})
    moved = np.flatnonzero(np.abs(pose.vertices - face.mesh.vertices).max(axis=1) > 1e-12)
    assert set(moved) <= set(face.rig.lids[fap].rows)
    others = [k for k, label in enumerate(face.mesh.fp_labels)
              if label != LIDS[fap][2] and label not in PASSIVE_POINTS + lid_corners(fap)]
    np.testing.assert_array_equal(pose.feature_points[others], face.neutral().feature_points[others])


def test_the_upper_margin_meets_the_lower_one_when_closed(generic_face):
    face = generic_face
    for fap in (19, 20):
        sheet = face.rig.lids[fap]
        pose = face.deform({fap: closing_value(face, fap)})
        lower = face.mesh.fp(LIDS[fap][3])
        upper_now = pose.vertices[sheet.point]
        assert upper_now[1] == pytest.approx(lower[1], abs=1e-9)


@pytest.mark.parametrize("upper, lower", [(1146, 369), (1000, 260), (1000, 520), (600, 600), (300, 200)])
def test_lids_closing_together_meet_and_never_pass(face, upper, lower):
    """A blink over a smile's raised lower lids (a visage stream sends 19/20 at 1146 over 21/22 at 369): the upper
    lid comes down onto the lower one and stops there; the lower lid moves its value x IRISD as alone. Before, the
    lids passed through each other and the skin folded (52 triangles in that frame)."""
    for up_fap, low_fap in ((19, 21), (20, 22)):
        pose = face.deform({up_fap: upper, low_fap: lower})
        up_i, low_i = face.mesh.fp_index(LIDS[up_fap][2]), face.mesh.fp_index(LIDS[low_fap][2])
        up_y, low_y = pose.feature_points[up_i][1], pose.feature_points[low_i][1]
        assert low_y - face.mesh.fp(LIDS[low_fap][2])[1] == pytest.approx(lower * face.fapu.unit("IRISD"), abs=1e-9)
        if upper / closing_value(face, up_fap) + lower / closing_value(face, low_fap) >= 1.0:
            assert up_y == pytest.approx(low_y, abs=1e-9)  # they meet ...
        else:
            assert up_y - face.mesh.fp(LIDS[up_fap][2])[1] == pytest.approx(-upper * face.fapu.unit("IRISD"), abs=1e-9)
        assert up_y >= low_y - 1e-9  # ... and never pass


def test_the_lids_of_both_deformers_agree(generic_face):
    fap_pose = generic_face.deform({19: 900, 22: 400})
    ark_pose = generic_face.with_deformer("arkit").deform({19: 900, 22: 400})
    for fap in (19, 22):
        rows = generic_face.rig.lids[fap].rows
        np.testing.assert_allclose(ark_pose.vertices[rows], fap_pose.vertices[rows], atol=1e-6)


@pytest.mark.parametrize("deformer", EXACT_DEFORMERS)
def test_expressions_and_blinks_keep_the_skin_outside_the_eyeballs(request, deformer):
    """The brows, cheeks and lids of every expression at full intensity, with the lids open, half
    and fully closed: no skin vertex comes within 0.05 mm of an eyeball (the lids rest 0.1 mm off it)."""
    from mpeg4fa.spec.profiles import EXPRESSION_PROFILES

    face = face_under(request, "generic", deformer)
    mesh = face.mesh
    eyes = []
    for eye, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        centre = mesh.vertices[mesh.joints[joint]]
        eyes.append((centre, np.linalg.norm(mesh.vertices[mesh.part(eye)] - centre, axis=1).max()))
    for name, profile in EXPRESSION_PROFILES.items():
        for lid in (0.0, 512.0, closing_value(face, 19)):
            values = profile.astype(float).copy()
            values[18] = values[19] = lid
            skin = face.pose_values(values).part("skin")
            for centre, radius in eyes:
                assert np.linalg.norm(skin - centre, axis=1).min() > radius + 0.05, (name, lid)
