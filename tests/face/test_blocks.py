"""The block deformer: 12-parameter linear fields per block, fitted by least squares, blended in.

The fit itself is checked on synthetic fields (exact recovery, each parameter's own motion,
coplanar points); on the faces: zero FAPs give the neutral mesh, FAPs outside the blocks
move exactly as with the feature-point deformer, those inside stay within the documented
errors (``blocks.FAP_ERRORS``), poses are mirror symmetric and the skin has no seam.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import face_under

from mpeg4fa.face import FaceError, motion, quality
from mpeg4fa.face.deformers import blocks
from mpeg4fa.face.deformers.blocks import (PARAMETERS, blocks_deformer, design_matrix, displacement,
                                           field_from_parameters, parameters_from_field, solve_parameters)
from mpeg4fa.spec import EXPRESSIONS, FAPS, N_FAPS, VISEMES
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES, VISEME_PROFILES

FLIP_X = np.array([-1.0, 1.0, 1.0])
STRAIN_LIMIT = 0.5  # the smooth-skin tests' limit: under it a pose passes whatever the other deformer does
LOOKS = ([VISEME_PROFILES["mpeg4"][v.name] for v in VISEMES if v.number]
         + [EXPRESSION_PROFILES[e.name] for e in EXPRESSIONS if e.number])


def _frame(fap: int, value: float) -> np.ndarray:
    v = np.zeros(N_FAPS)
    v[fap - 1] = value
    return v


def _look(values) -> np.ndarray:
    v = np.asarray(values, dtype=float).copy()
    v[:2] = 0
    return v


@pytest.fixture(scope="session")
def generic_blocks(request):
    return face_under(request, "generic", "blocks")  # one per session (tests/conftest.py)


@pytest.fixture(scope="session")
def procedural_blocks(request):
    return face_under(request, "procedural", "blocks")  # one per session (tests/conftest.py)


# ---------------------------------------------------------------- the fit


def _random_points(rng, n=9):
    return rng.normal(size=(n, 3)) * [30.0, 20.0, 10.0] + [20.0, 700.0, 140.0]


@pytest.mark.parametrize("seed", range(5))
def test_parameters_recovered_exactly_from_a_linear_field(seed):
    rng = np.random.default_rng(seed)
    points = _random_points(rng)
    x0 = points[0] + rng.normal(size=3)
    params = np.concatenate([rng.normal(size=3) * 5.0, rng.normal(size=9) * 0.05])
    u = displacement(params, points, x0)
    assert np.abs(solve_parameters(points, x0, u) - params).max() < 1e-9
    # the same least squares as the 12-column design matrix
    lstsq = np.linalg.lstsq(design_matrix(points, x0), u.ravel(), rcond=None)[0]
    assert np.abs(lstsq - params).max() < 1e-9


def test_parameters_recovered_on_the_face_blocks(generic_blocks):
    """The real blocks' points (4 to 12 of them), random fields, batched."""
    rng = np.random.default_rng(7)
    mesh = generic_blocks.mesh
    for block in generic_blocks.posing.blocks:
        points = mesh.vertices[mesh.fp_vertex[block.fp]]
        params = np.concatenate([rng.normal(size=(20, 3)) * 5.0, rng.normal(size=(20, 9)) * 0.05], axis=1)
        u = np.stack([displacement(p, points, block.reference) for p in params])
        assert np.abs(solve_parameters(points, block.reference, u) - params).max() < 1e-9, block.name


def test_parameter_round_trip():
    p = np.arange(1.0, 13.0) / 10
    assert np.allclose(parameters_from_field(*field_from_parameters(p)), p, rtol=0, atol=1e-15)


def _alone(name: str, value: float = 0.01) -> np.ndarray:
    p = np.zeros(12)
    p[PARAMETERS.index(name)] = value
    return p


def test_each_parameter_makes_its_named_motion():
    rng = np.random.default_rng(3)
    x0 = np.array([1.0, 2.0, 3.0])
    points = _random_points(rng, 6)
    r = points - x0
    e = 0.01
    expected = {
        "u0": np.tile([e, 0, 0], (6, 1)), "v0": np.tile([0, e, 0], (6, 1)), "w0": np.tile([0, 0, e], (6, 1)),
        # small rotations (right-handed): rx turns y toward z, ry z toward x, rz x toward y
        "rx": e * np.column_stack([0 * r[:, 0], -r[:, 2], r[:, 1]]),
        "ry": e * np.column_stack([r[:, 2], 0 * r[:, 0], -r[:, 0]]),
        "rz": e * np.column_stack([-r[:, 1], r[:, 0], 0 * r[:, 0]]),
        # normal strains stretch along their axis only
        "ex": e * np.column_stack([r[:, 0], 0 * r[:, 0], 0 * r[:, 0]]),
        "ey": e * np.column_stack([0 * r[:, 0], r[:, 1], 0 * r[:, 0]]),
        "ez": e * np.column_stack([0 * r[:, 0], 0 * r[:, 0], r[:, 2]]),
        # engineering shear: the right angle between the two axes closes by the value
        "txy": e / 2 * np.column_stack([r[:, 1], r[:, 0], 0 * r[:, 0]]),
        "txz": e / 2 * np.column_stack([r[:, 2], 0 * r[:, 0], r[:, 0]]),
        "tyz": e / 2 * np.column_stack([0 * r[:, 0], r[:, 2], r[:, 1]]),
    }
    assert set(expected) == set(PARAMETERS)
    for name, want in expected.items():
        assert np.allclose(displacement(_alone(name, e), points, x0), want, rtol=0, atol=1e-12), name
    # a pure txy changes the angle between the x and y axes by txy (to first order)
    t, m = field_from_parameters(_alone("txy", e))
    ax, ay = (np.eye(3) + m)[:, 0], (np.eye(3) + m)[:, 1]
    angle = np.arccos(ax @ ay / np.linalg.norm(ax) / np.linalg.norm(ay))
    assert abs((np.pi / 2 - angle) - e) < 1e-4


def test_coplanar_points_leave_the_missing_direction_unstrained():
    rng = np.random.default_rng(5)
    points = rng.normal(size=(8, 3)) * [30.0, 20.0, 0.0]  # all in z = 0
    x0 = np.zeros(3)
    params = np.concatenate([rng.normal(size=3), rng.normal(size=9) * 0.05])
    u = displacement(params, points, x0)
    solved = solve_parameters(points, x0, u)
    assert np.all(np.isfinite(solved))
    t, m = field_from_parameters(solved)
    assert np.abs(m[:, 2]).max() < 1e-12  # no variation along z, which the points do not span
    assert np.abs(displacement(solved, points, x0) - u).max() < 1e-9  # and the points still fit exactly
    # nearly coplanar (1e-4 of the spread): damped, not amplified
    flat = points + [0.0, 0.0, 1.0] * rng.normal(size=(8, 1)) * 1e-3
    noisy = u + rng.normal(size=u.shape) * 0.01
    _, m = field_from_parameters(solve_parameters(flat, x0, noisy))
    assert np.abs(m[:, 2]).max() < 1.0


def test_too_few_points_refused():
    with pytest.raises(FaceError, match="at least 4"):
        solve_parameters(np.eye(3), np.zeros(3), np.zeros((3, 3)))


# ---------------------------------------------------------------- on the faces


@pytest.mark.parametrize("name", ["procedural", "generic"])
def test_zero_faps_give_the_neutral_mesh(request, name):
    face = request.getfixturevalue(f"{name}_blocks")
    assert np.array_equal(face.deform(np.zeros(N_FAPS)).vertices, face.mesh.vertices)


def test_no_blocks_is_the_feature_point_deformer(procedural_face):
    d = blocks_deformer(procedural_face.mesh, procedural_face.rig, regions=())
    for values in LOOKS[:5]:
        v = _look(values)
        assert np.array_equal(d(v).vertices, procedural_face.deform(v).vertices)


def test_region_choices(procedural_face):
    mesh, rig = procedural_face.mesh, procedural_face.rig
    with pytest.raises(FaceError, match="unknown block"):
        blocks_deformer(mesh, rig, regions=("nose",))
    with pytest.raises(FaceError, match="same skin"):
        blocks_deformer(mesh, rig, regions=("mouth", "lip_t"))
    only_eyes = blocks_deformer(mesh, rig, regions=("eye_l", "eye_r"))
    v = _frame(4, 200)  # a lip FAP: exact without the lip blocks
    assert np.array_equal(only_eyes(v).vertices, procedural_face.deform(v).vertices)
    one = blocks_deformer(mesh, rig, regions=("eye_l", "eye_r", "mouth"))
    assert [b.name for b in one.blocks] == ["eye_l", "eye_r", "mouth"]
    assert [b.name for b in blocks_deformer(mesh, rig).blocks] == list(blocks.REGIONS)


def _fap_error(face, base, fap: int) -> tuple[float, float]:
    """(own point's error, other points' drift from the feature-point deformer), relative to value x FAPU."""
    record = FAPS[fap - 1]
    rest = face.mesh.feature_points()
    index = {label: i for i, label in enumerate(face.mesh.fp_labels)}
    own_i = [index[label] for label in record.feature_point]
    own = other = 0.0
    for value in ((200.0,) if record.unidirectional else (200.0, -200.0)):
        amount = value * face.fapu.unit(record.fapu)
        moved = face.deform(_frame(fap, value)).feature_points
        wanted = base.deform(_frame(fap, value)).feature_points
        for i in own_i:
            own = max(own, float(np.linalg.norm(moved[i] - rest[i] - amount * motion.direction(fap))) / abs(amount))
        mask = np.ones(len(rest), bool)
        mask[own_i] = False
        other = max(other, float(np.linalg.norm(moved[mask] - wanted[mask], axis=1).max()) / abs(amount))
    return own, other


def test_fapu_errors_within_the_documented_table(generic_face, generic_blocks):
    """Every FAP alone: its point within FAP_ERRORS of value x FAPU, other points within FAP_ERRORS
    of the feature-point deformer's; FAPs not listed exact (jaw, lids, eyes and head included)."""
    bad = []
    for fap in range(3, N_FAPS + 1):
        own_limit, other_limit = blocks.FAP_ERRORS.get(fap, (1e-9, 1e-9))
        if motion.kind(fap) != "translate":  # no FAPU translation of one point: compare whole poses
            for value in ((200.0,) if FAPS[fap - 1].unidirectional else (200.0, -200.0)):
                a = generic_blocks.deform(_frame(fap, value)).feature_points
                b = generic_face.deform(_frame(fap, value)).feature_points
                if np.abs(a - b).max() > 1e-9:
                    bad.append((fap, "differs from the feature-point deformer"))
            continue
        own, other = _fap_error(generic_blocks, generic_face, fap)
        if own > own_limit + 1e-9 or other > other_limit + 1e-9:
            bad.append((fap, own, other, own_limit, other_limit))
    assert not bad


def test_block_parameters_read_as_the_motion(generic_blocks):
    d = generic_blocks.posing
    both_stretch = _frame(6, 200) + _frame(7, 200) + _frame(53, 200) + _frame(54, 200)
    p = dict(zip(PARAMETERS, d.parameters(both_stretch)["lip_t"]))
    assert p["ex"] > 0.02  # corners out: the lip stretches along x
    assert abs(p["u0"]) < 1e-9 and abs(p["rz"]) < 1e-9 and abs(p["txy"]) < 1e-9  # symmetric
    brows = sum(_frame(f, 200) for f in range(31, 37))
    params = d.parameters(brows)
    left, right = (dict(zip(PARAMETERS, params[k])) for k in ("eye_l", "eye_r"))
    assert left["v0"] > 0 and left["ey"] > 0  # brows up above fixed eye corners: the block stretches up
    # the right block is the mirror image: x-odd parameters flip their sign
    odd = {"u0", "ry", "rz", "txy", "txz"}
    for name in PARAMETERS:
        assert abs(left[name] - (-1.0 if name in odd else 1.0) * right[name]) < 1e-9, name


def test_poses_are_mirror_symmetric(generic_blocks):
    mesh = generic_blocks.mesh
    for values in (VISEME_PROFILES["mpeg4"]["ou"], EXPRESSION_PROFILES["surprise"], EXPRESSION_PROFILES["joy"]):
        v = generic_blocks.deform(_look(values)).vertices
        assert np.abs(v[mesh.mirror] * FLIP_X - v).max() < 1e-6
    a = generic_blocks.deform(_frame(31, 300)).vertices
    b = generic_blocks.deform(_frame(32, 300)).vertices
    assert np.abs(a[mesh.mirror] * FLIP_X - b).max() < 1e-6


def test_weights_fade_smoothly_to_the_border(generic_blocks):
    """No step: each block weight is 1 on its own points, 0 on every other feature point, and
    changes across a skin edge by at most the edge's length over the band (plus the clearances)."""
    mesh = generic_blocks.mesh
    d = generic_blocks.posing
    edges = quality.skin_graph(mesh).edges
    length = np.linalg.norm(mesh.vertices[edges[:, 0]] - mesh.vertices[edges[:, 1]], axis=1)
    for b in d.blocks:
        spec = blocks.block_specs()[b.name]
        w = np.zeros(mesh.n_vertices)
        w[b.rows] = b.weight
        others = [i for i, label in enumerate(mesh.fp_labels)
                  if label not in spec.points and label not in ("3.9", "3.10", "3.13", "3.14")]
        assert np.all(w[mesh.fp_vertex[others]] == 0), b.name
        slope = np.abs(w[edges[:, 0]] - w[edges[:, 1]]) / length
        # smooth_down's slope is at most 1.5 / width; three fades multiply
        limit = 1.5 * (1 / spec.band_mm + 1 / spec.clear_mm + 1 / 6.0)
        assert slope.max() <= limit, b.name


def test_no_seam_in_visemes_and_expressions(generic_face, generic_blocks):
    """The blended skin strains no more than 1.5x the feature-point deformer's (or under 0.5), and
    folds at most a few triangles more (measured: 24 in all these looks against the other's 430)."""
    mesh = generic_face.mesh
    graph = quality.skin_graph(mesh)
    for values in LOOKS:
        v = _look(values)
        a = quality.measure(mesh, generic_blocks.deform(v).vertices, graph)
        b = quality.measure(mesh, generic_face.deform(v).vertices, graph)
        assert a.max_strain <= max(1.5 * b.max_strain, STRAIN_LIMIT), a.describe()
        assert a.folded <= b.folded + 12, (a.describe(), b.describe())


def test_displacement_continuous_across_the_border(generic_blocks):
    """Along a path leaving the mouth block (8.3 outward to the cheek), the blocks pose moves
    neighbouring vertices by nearly the same amount: no jump where the weight reaches 0."""
    mesh = generic_blocks.mesh
    v = _look(EXPRESSION_PROFILES["joy"])
    d = generic_blocks.deform(v).vertices - mesh.vertices
    start = mesh.fp("8.3")
    skin = mesh.part("skin")
    local = mesh.vertices[skin]
    # vertices near the line from 8.3 outward-upward, sorted by distance along it
    direction = np.array([1.0, 0.3, -0.6]) / np.linalg.norm([1.0, 0.3, -0.6])
    rel = local - start
    along = rel @ direction
    off = np.linalg.norm(rel - np.outer(along, direction), axis=1)
    path = np.flatnonzero((off < 4.0) & (along > 0) & (along < 40))
    path = path[np.argsort(along[path])]
    steps = np.linalg.norm(np.diff(d[skin][path], axis=0), axis=1)
    gaps = np.diff(along[path])
    assert len(path) > 5
    # relative to how far the skin moves there (0.6 per mm + 0.3 mm when joy moved it 5.6 mm at most)
    scale = np.linalg.norm(d[skin][path], axis=1).max() / 5.6
    assert np.all(steps <= scale * (0.6 * np.maximum(gaps, 1.0) + 0.3))


def test_registered(procedural_face):
    from mpeg4fa.face import deformers

    assert "blocks" in deformers.names()
    d = deformers.build("blocks", procedural_face.mesh, procedural_face.rig)
    assert isinstance(d, blocks.BlocksDeformer)
