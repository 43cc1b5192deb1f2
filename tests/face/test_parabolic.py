"""The parabolic eye model (mpeg4fa.face.deformers.parabolic, mpeg4fa.face.eyes).

Eyeballs are fitted spheres turning about their centres; each lid contour is a parabola
through the eye's corners and its lid point, closing with the corners fixed. The FAPU
semantics are the feature-point deformer's (the lid point moves value x IRISD vertically),
the closed margins meet, no lid vertex enters an eyeball, and away from FAPs 19-28 the pose
is the feature-point deformer's.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import face_under

from mpeg4fa.face import motion
from mpeg4fa.face.couplings import PASSIVE_POINTS
from mpeg4fa.face.deformers.parabolic import LID_CLEARANCE_MM, build_eyes
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.eyes import EyeFrame, Parabola, fit_sphere, middle_share
from mpeg4fa.face.lids import LIDS, OVERLAP_MM
from mpeg4fa.spec import FAPS, N_FAPS
from test_fap_semantics import fap_errors
from test_lids import closing_value

LID_FAPS = sorted(LIDS)
EYE_FAPS = list(range(19, 29))
FLIP_X = np.array([-1.0, 1.0, 1.0])
MIRRORED = ((19, 20, 1.0), (21, 22, 1.0), (23, 24, -1.0), (25, 26, 1.0), (27, 28, 1.0))  # eye yaw: both positive to the left


@pytest.fixture(scope="session")
def generic_parabolic(request):
    return face_under(request, "generic", "parabolic")  # one per session (tests/conftest.py)


@pytest.fixture(scope="session")
def procedural_parabolic(request):
    return face_under(request, "procedural", "parabolic")  # one per session (tests/conftest.py)


@pytest.fixture(scope="module", params=["procedural", "generic"])
def face(request):
    """Each face posed by the parabolic deformer (built once per module)."""
    return request.getfixturevalue(f"{request.param}_parabolic")


def _frame(**values: float) -> np.ndarray:
    v = np.zeros(N_FAPS)
    for key, value in values.items():
        v[int(key[1:]) - 1] = value
    return v


def _lid(face, fap):
    return face.posing.lids[fap]


# -- the geometry ------------------------------------------------------------------------------


def test_parabola_through_three_points_is_exact():
    rng = np.random.default_rng(3)
    for _ in range(200):
        x = np.sort(rng.uniform(-20, 20, 3))
        if np.diff(x).min() < 0.5:
            continue
        y = rng.uniform(-5, 5, 3)
        p = Parabola.through(*np.c_[x, y])
        np.testing.assert_allclose(p(x), y, rtol=0, atol=1e-9)


def test_parabola_refuses_points_on_a_line_or_above_each_other():
    with pytest.raises(FaceError):
        Parabola.through((0, 0), (1, 1), (2, 2))
    with pytest.raises(FaceError):
        Parabola.through((0, 0), (0, 1), (2, 2))


def test_each_lid_contour_passes_through_its_three_feature_points(face):
    mesh = face.mesh
    for fap, (_, _, point, _, lateral, medial, _) in LIDS.items():
        lid = _lid(face, fap)
        xy = lid.frame.to_frame(np.array([mesh.fp(lateral), mesh.fp(point), mesh.fp(medial)]))
        np.testing.assert_allclose(xy[[0, 2], 1], 0.0, atol=1e-9)  # the corners are the frame's x axis
        np.testing.assert_allclose(lid.parabola(xy[:, 0]), xy[:, 1], atol=1e-9)
        assert lid.parabola.b == pytest.approx(0.0, abs=1e-9)  # the apex is above the corners' midpoint
        assert (lid.parabola.a < 0) == (lid.side == "upper")  # upper lid arched up, lower down


def test_closing_changes_a_and_c_and_keeps_the_corners(face):
    for fap in LID_FAPS:
        lid = _lid(face, fap)
        (x1, x2), m = lid.corners_x, lid.middle_x
        h2 = ((x1 - x2) / 2) ** 2
        y_m = float(lid.parabola(m))
        for d in (-2.0, 1.0, lid.full / 2, lid.full, 1.3 * lid.full):
            c = lid.contour(d)
            np.testing.assert_allclose(c(np.array([x1, x2])), 0.0, atol=1e-9)  # corners fixed
            assert c(m) == pytest.approx(y_m + lid.sign * d, abs=1e-9)  # the lid point moves by d
            assert c.b == pytest.approx(lid.parabola.b, abs=1e-9)
            assert c.c - lid.parabola.c == pytest.approx(lid.sign * d * h2 / (h2 - m * m), abs=1e-9)
            x = np.linspace(x2, x1, 7)
            np.testing.assert_allclose(c(x) - lid.parabola(x), lid.sign * d * middle_share(x, (x1, x2), m),
                                       atol=1e-9)


def test_closed_upper_contour_is_the_lower_contour(generic_parabolic):
    """Both parabolas pass through the corners; closed, the upper one passes through the lower
    lid point's height: the two nearly coincide (the lid points are 0.4 mm apart in x)."""
    face = generic_parabolic
    for up, low in ((19, 21), (20, 22)):
        upper, lower = _lid(face, up), _lid(face, low)
        x = np.linspace(*upper.corners_x, 21)
        assert np.abs(upper.contour(upper.full)(x) - lower.parabola(x)).max() < 0.05


def test_sphere_fit_recovers_a_sphere_and_refuses_a_plane():
    rng = np.random.default_rng(5)
    d = rng.normal(size=(400, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    centre = np.array([3.0, -700.0, 120.0])
    s = fit_sphere(centre + 11.5 * d)
    np.testing.assert_allclose(s.centre, centre, atol=1e-9)
    assert s.radius == pytest.approx(11.5, abs=1e-9) and s.max_residual < 1e-9
    noisy = fit_sphere(centre + (11.5 + rng.normal(0, 0.05, (400, 1))) * d)
    assert np.linalg.norm(noisy.centre - centre) < 0.02 and abs(noisy.radius - 11.5) < 0.02
    assert 0.03 < noisy.rms_residual < 0.07
    with pytest.raises(FaceError):
        fit_sphere(np.c_[rng.normal(size=(50, 2)), np.zeros(50)])


def test_eye_frame_is_a_vertical_shear():
    frame = EyeFrame.from_corners(np.array([40.0, 10.0, 0.0]), np.array([20.0, 8.0, 3.0]))
    xy = frame.to_frame(np.array([[40.0, 10.0, 0.0], [20.0, 8.0, 3.0], [30.0, 12.0, 1.0], [30.0, 11.0, 5.0]]))
    np.testing.assert_allclose(xy[:2, 1], 0.0, atol=1e-12)
    assert xy[2, 1] - xy[3, 1] == pytest.approx(1.0)  # vertical distances are kept


def test_the_eye_parts_are_spheres_about_their_joints(face):
    for eye, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        s = face.posing.eyes[eye].sphere
        assert s.rms_residual < 1e-9 * s.radius and s.max_residual < 1e-9 * s.radius
        np.testing.assert_allclose(s.centre, face.mesh.joint(joint), atol=1e-9)


def test_an_eye_that_is_no_sphere_is_refused(procedural_face):
    mesh = procedural_face.mesh
    v = mesh.vertices.copy()
    eye = mesh.part("eye_l")
    centre = mesh.joint("l-eye")
    v[eye] = centre + (v[eye] - centre) * np.array([1.0, 0.5, 1.0])
    with pytest.raises(FaceError, match="not a sphere"):
        build_eyes(mesh.with_vertices(v))


# -- the lids ----------------------------------------------------------------------------------


@pytest.mark.parametrize("fap", LID_FAPS)
def test_the_lid_point_moves_value_times_irisd_on_its_arc(face, fap):
    _, joint, point, *_ = LIDS[fap]
    i = face.mesh.fp_index(point)
    lid = _lid(face, fap)
    centre = face.mesh.joint(joint)
    rest = face.mesh.fp(point)
    for value in (-200, 100, 512, closing_value(face, fap), 1.2 * closing_value(face, fap)):
        now = face.deform({fap: value}).feature_points[i]
        assert now[1] - rest[1] == pytest.approx(lid.sign * value * face.fapu.unit("IRISD"), abs=1e-9)
        assert now[0] == rest[0]
        assert np.linalg.norm((now - centre)[1:]) == pytest.approx(np.linalg.norm((rest - centre)[1:]), abs=1e-9)


@pytest.mark.parametrize("fap", LID_FAPS)
def test_the_eye_corners_never_move(face, fap):
    _, _, _, _, lateral, medial, _ = LIDS[fap]
    corners = [face.mesh.fp_index(lateral), face.mesh.fp_index(medial)]
    for value in (-300, 400, closing_value(face, fap), 1.5 * closing_value(face, fap)):
        pose = face.deform({fap: value})
        np.testing.assert_array_equal(pose.feature_points[corners], face.mesh.feature_points()[corners])


@pytest.mark.parametrize("fap", LID_FAPS)
def test_closed_margins_meet(face, fap):
    """At the closing value every vertex of the moving margin is on the opposite margin (at most
    OVERLAP_MM past it), the lid point at the opposite lid point's height (the FAPU semantics;
    on the coarse procedural head 3.3 is a dip in its margin); halfway it is halfway."""
    opposite = LIDS[fap][3]
    lid = _lid(face, fap)
    rest = face.mesh.vertices
    other = face.posing.lids[next(f for f, row in LIDS.items() if row[2] == opposite)].margin
    inner = lid.margin[1:-1]
    inner = inner[inner != lid.point]
    order = np.argsort(rest[other, 0])

    def gap(pose):  # how far each moving margin vertex still is from the opposite margin (>0: open)
        y_other = np.interp(pose[inner, 0], rest[other[order], 0], rest[other[order], 1])
        return lid.sign * (y_other - pose[inner, 1])

    closed = face.deform({fap: closing_value(face, fap)}).vertices
    assert closed[lid.point, 1] == pytest.approx(face.mesh.fp(opposite)[1], abs=1e-9)
    g = gap(closed)
    assert g.max() <= 1e-9, g.max()
    assert g.min() >= -OVERLAP_MM - 1e-9, g.min()
    half = face.deform({fap: closing_value(face, fap) / 2}).vertices
    np.testing.assert_allclose(gap(half), (gap(rest) + g) / 2, atol=1e-9)


@pytest.mark.parametrize("fap", LID_FAPS)
def test_no_lid_vertex_enters_the_eyeball(face, fap):
    eye, joint = LIDS[fap][:2]
    sphere = face.posing.eyes[eye].sphere
    rest = np.linalg.norm(face.mesh.vertices[face.mesh.part("skin")] - sphere.centre, axis=1)
    assert rest[_lid(face, fap).rows].min() > sphere.radius + LID_CLEARANCE_MM
    close = closing_value(face, fap)
    for value in np.linspace(-300, 1.2 * close, 9):
        r = np.linalg.norm(face.deform({fap: value}).part("skin") - sphere.centre, axis=1)
        np.testing.assert_allclose(r, rest, atol=1e-9)  # every lid vertex slides on its own sphere


@pytest.mark.parametrize("fap", LID_FAPS)
def test_only_the_lid_sheet_and_its_point_move(face, fap):
    pose = face.deform({fap: 600})
    moved = np.flatnonzero(np.abs(pose.vertices - face.mesh.vertices).max(axis=1) > 1e-12)
    assert set(moved) <= set(face.rig.lids[fap].rows)
    others = [k for k, label in enumerate(face.mesh.fp_labels)
              if label != LIDS[fap][2] and label not in PASSIVE_POINTS]
    np.testing.assert_array_equal(pose.feature_points[others], face.mesh.feature_points()[others])


def test_expressions_and_blinks_keep_the_skin_outside_the_eyeballs(generic_parabolic):
    """As the feature-point deformer's lid test: every expression at full intensity, lids open,
    half and fully closed (both upper, and both upper and lower halfway), no skin vertex within
    0.05 mm of an eyeball."""
    from mpeg4fa.spec.profiles import EXPRESSION_PROFILES

    face = generic_parabolic
    spheres = [e.sphere for e in face.posing.eyes.values()]
    close = closing_value(face, 19)
    for name, profile in EXPRESSION_PROFILES.items():
        for upper, lower in ((0.0, 0.0), (512.0, 0.0), (close, 0.0), (close / 2, close / 2)):
            values = profile.astype(float).copy()
            values[18] = values[19] = upper
            values[20] = values[21] = lower
            skin = face.pose_values(values).part("skin")
            for s in spheres:
                assert np.linalg.norm(skin - s.centre, axis=1).min() > s.radius + 0.05, (name, upper, lower)


# -- the eyeballs ------------------------------------------------------------------------------


def test_eye_rotation_keeps_every_eye_vertex_on_its_sphere(face):
    for yaw, pitch in ((300, 0), (0, -250), (-400, 350)):
        pose = face.deform(_frame(f23=yaw, f25=pitch, f24=-yaw, f26=pitch))
        for eye in ("eye_l", "eye_r"):
            s = face.posing.eyes[eye].sphere
            r = np.linalg.norm(pose.part(eye) - s.centre, axis=1)
            np.testing.assert_allclose(r, s.radius, atol=1e-9)
        # the skin stays, but for the lids that ride on the eyes' pitch (face/lids.py lid_drops)
        moved = np.flatnonzero(np.any(pose.vertices != face.mesh.vertices, axis=1))
        skin = face.mesh.part("skin")
        lids = np.concatenate([sheet.rows for sheet in face.rig.lids.values()])
        assert np.isin(moved[(moved >= skin.start) & (moved < skin.stop)], lids).all()


def test_eye_turn_and_thrust_together(face):
    """Yaw and pitch turn the eye rigidly about its centre, the thrust then pushes it forward."""
    es, au = face.fapu.unit("ES"), face.fapu.unit("AU")
    pose = face.deform(_frame(f23=200, f25=-150, f27=100))
    s = face.posing.eyes["eye_l"].sphere
    turn = motion.rotation_matrix(1, 200 * au) @ motion.rotation_matrix(0, -150 * au)
    rest = face.mesh.vertices[face.mesh.part("eye_l")]
    expected = s.centre + (rest - s.centre) @ turn.T + np.array([0, 0, 100 * es])
    np.testing.assert_allclose(pose.part("eye_l"), expected, atol=1e-9)
    assert pose.vertices[face.mesh.joints["l-eye"]] == pytest.approx(face.mesh.joint("l-eye") + [0, 0, 100 * es])


@pytest.mark.parametrize("fap", EYE_FAPS)
def test_eye_faps_move_their_points_by_value_times_fapu(face, fap):
    for sign in (1.0,) if FAPS[fap - 1].unidirectional else (1.0, -1.0):
        errors = fap_errors(face, fap, sign * 200.0)
        bad = [(what, err) for what, err in errors if not err < 1e-6]
        assert not bad, f"FAP {fap} ({FAPS[fap - 1].name}) = {sign * 200:g}: {bad}"


# -- symmetry and the rest of the face ---------------------------------------------------------


@pytest.mark.parametrize("left,right,sign", MIRRORED, ids=[f"{a}-{b}" for a, b, _ in MIRRORED])
def test_mirrored_faps_give_mirrored_poses(face, left, right, sign):
    mesh = face.mesh
    for value in (300.0, -300.0, closing_value(face, 19) if left in LIDS else 500.0):
        a = face.deform(_frame(**{f"f{left}": value})).vertices
        b = face.deform(_frame(**{f"f{right}": sign * value})).vertices
        assert np.abs(b[mesh.mirror] * FLIP_X - a).max() <= 1e-6, (left, right, value)


@pytest.mark.parametrize("fap", [19, 21, 23, 25, 27])
def test_left_faps_move_only_the_left_side(face, fap):
    x = face.mesh.vertices[:, 0]
    d = np.linalg.norm(face.deform(_frame(**{f"f{fap}": 400.0})).vertices - face.mesh.vertices, axis=1)
    assert d.max() > 0 and x[d > 0].min() > 0


def test_without_eye_faps_the_pose_is_the_feature_point_deformers(face):
    rng = np.random.default_rng(11)
    values = rng.normal(0, 150, (5, N_FAPS))
    values[:, :2] = 0
    values[:, 18:28] = 0
    fap_face = face.with_deformer("fap")
    for v in values:
        np.testing.assert_array_equal(face.pose_values(v).vertices, fap_face.pose_values(v).vertices)


def test_the_head_turns_the_closed_lids_and_turned_eyes_with_it(face):
    """Lids and eyes are posed in the head's frame, then the head turns (FAP 49, yaw)."""
    v = _frame(f19=closing_value(face, 19), f23=300, f49=2000)
    still = v.copy()
    still[48] = 0
    turned, straight = face.deform(v), face.deform(still)
    centre = face.mesh.fp("7.1")
    r = motion.head_rotation(0.0, 2000 * face.fapu.unit("AU"), 0.0)
    eye = face.mesh.part("eye_l")
    np.testing.assert_allclose(turned.vertices[eye], centre + (straight.vertices[eye] - centre) @ r.T, atol=1e-9)
