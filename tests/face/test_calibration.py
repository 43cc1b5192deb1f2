"""Calibration: fitting a head to the feature points of an FDP.

Targets are made by a known smooth map of the head's own feature points (scale
1.1, a 5 degree rotation, a shift and a smooth bump), so that the right answer
is known: sent points land exactly, FAPU are measured anew, the mesh does not
fold, and points that were not sent follow.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from mpeg4fa.face.calibrate import ALIGNMENTS, METHODS, calibrate_mesh
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.fapu import DISTANCES, measure_fapu
from mpeg4fa.face.model import FaceModel

try:  # the real FDP type when the fdp package is there; a stand-in with the two fields otherwise
    from mpeg4fa.fdp import Fdp as _Fdp

    def make_fdp(labels, points):
        return _Fdp(labels=tuple(labels), points=np.asarray(points, dtype=np.float64))
except ImportError:  # pragma: no cover - depends on the checkout
    make_fdp = None


@dataclass(frozen=True)
class StandIn:
    """What FaceModel.calibrate reads from an FDP, with no checks of its own."""

    labels: tuple[str, ...]
    points: np.ndarray


if make_fdp is None:  # pragma: no cover
    def make_fdp(labels, points):
        return StandIn(tuple(labels), np.asarray(points, dtype=np.float64))


LIPS = tuple(f"2.{k}" for k in range(2, 10)) + tuple(f"8.{k}" for k in range(1, 11))
CASES = [(m, a) for m in METHODS for a in ALIGNMENTS]


def _rotation(axis, degrees: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    a = np.radians(degrees)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(a) * k + (1 - np.cos(a)) * k @ k


def similarity_map(mesh):
    centre = mesh.feature_points().mean(axis=0)
    rot = _rotation([0.3, 1.0, 0.2], 5.0)
    shift = np.array([4.0, -7.0, 3.0])
    return lambda p: (1.1 * (np.asarray(p) - centre)) @ rot.T + centre + shift


def smooth_map(mesh):
    """Scale 1.1, 5 degrees about a tilted axis, a shift, and a bump of 4 mm over the cheek and jaw."""
    sim = similarity_map(mesh)
    height = mesh.height()
    bump_at = mesh.fp("5.1") * np.array([1.0, 1.0, 1.0])
    width = 0.25 * height

    def warp(p):
        p = np.asarray(p, dtype=float)
        g = np.exp(-((p - bump_at) ** 2).sum(axis=-1) / (2 * width ** 2))
        return sim(p) + 4.0 * g[..., None] * np.array([0.6, -0.3, 0.75])

    return warp


@pytest.fixture(scope="module", params=["procedural", "generic"])
def base(request) -> FaceModel:
    return request.getfixturevalue(f"{request.param}_face")


def _targets(face: FaceModel, labels, mapping) -> np.ndarray:
    return mapping(np.array([face.mesh.fp(label) for label in labels]))


@pytest.mark.parametrize("method,alignment", CASES)
def test_all_points_land(base, method, alignment, capsys):
    mesh = base.mesh
    labels = mesh.fp_labels
    targets = _targets(base, labels, smooth_map(mesh))
    face = base.calibrate(make_fdp(labels, targets), method=method, alignment=alignment)
    report = face.calibration
    height = mesh.height()
    got = np.array([face.mesh.fp(label) for label in labels])
    assert np.abs(got - targets).max() <= 1e-6 * height
    assert report.max_error_relative <= 1e-6
    assert report.method == method and report.alignment == alignment
    assert "11.5" not in report.labels and len(report.labels) == 83
    # FAPU are measured on the calibrated face
    expected = measure_fapu(dict(zip(labels, targets)))
    for symbol in DISTANCES:
        assert getattr(face.fapu, f"{symbol}0") == pytest.approx(getattr(expected, f"{symbol}0"), rel=1e-6)
    # a sane mesh: nothing folded, quality reported
    assert report.folded_triangles == 0
    assert 0 < report.min_quality_before <= 1 and 0 < report.min_quality_after <= 1
    if mesh.face_units is not None:  # the generic head
        assert report.min_quality_after > 0.25 * report.min_quality_before
    with capsys.disabled():
        print(f"\n[{mesh.source}] {method}/{alignment}: min triangle quality "
              f"{report.min_quality_before:.3f} -> {report.min_quality_after:.3f}, "
              f"max error {report.max_error:.2e} mm, {report.seconds:.2f} s")
    # the eyeballs move rigidly after the alignment: spheres stay spheres about their moved centres
    # (bbox alignment scales the axes unequally, eyeballs included, so they become slight ellipsoids)
    for part, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        offset = face.mesh.vertices[face.mesh.part(part)] - face.mesh.joint(joint)
        if alignment == "bbox":
            rest = mesh.vertices[mesh.part(part)] - mesh.joint(joint)
            axis_scale = np.ptp(offset, axis=0) / np.ptp(rest, axis=0)
            assert np.abs(offset - rest * axis_scale).max() <= 1e-9 * height
        else:
            assert np.ptp(np.linalg.norm(offset, axis=1)) <= 1e-9 * height


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("subset", ["lips", "ten random"])
def test_similarity_subset_moves_everything(base, method, subset):
    """With a pure similarity as the target, a few points fix it: the whole head follows exactly."""
    mesh = base.mesh
    labels = LIPS if subset == "lips" else tuple(np.random.default_rng(7).choice(mesh.fp_labels, 10, replace=False))
    mapping = similarity_map(mesh)
    face = base.calibrate(make_fdp(labels, _targets(base, labels, mapping)), method=method)
    assert np.abs(face.mesh.vertices - mapping(mesh.vertices)).max() <= 1e-6 * mesh.height()


@pytest.mark.parametrize("method,alignment", CASES)
@pytest.mark.parametrize("subset", ["lips", "ten random"])
def test_subset_lands_and_the_rest_follow(base, method, alignment, subset):
    mesh = base.mesh
    rng = np.random.default_rng(11)
    labels = LIPS if subset == "lips" else tuple(rng.choice([x for x in mesh.fp_labels if x != "11.5"], 10,
                                                           replace=False))
    mapping = smooth_map(mesh)
    targets = _targets(base, labels, mapping)
    face = base.calibrate(make_fdp(labels, targets), method=method, alignment=alignment)
    height = mesh.height()
    got = np.array([face.mesh.fp(label) for label in labels])
    assert np.abs(got - targets).max() <= 1e-6 * height
    assert face.calibration.folded_triangles == 0
    assert np.isfinite(face.mesh.vertices).all()
    rest = [x for x in mesh.fp_labels if x not in labels]
    before = np.linalg.norm(_targets(base, rest, mapping) - [mesh.fp(x) for x in rest], axis=1)
    after = np.linalg.norm(_targets(base, rest, mapping) - [face.mesh.fp(x) for x in rest], axis=1)
    if alignment == "none":  # no global fit: the warp alone carries the neighbours part of the way
        assert after.mean() < before.mean()
    else:
        assert after.mean() < 0.5 * before.mean(), (after.mean(), before.mean())


@pytest.mark.parametrize("method,alignment", CASES)
def test_single_point_translates(base, method, alignment):
    mesh = base.mesh
    shift = np.array([3.0, -2.0, 5.0])
    target = mesh.fp("9.3") + shift
    face = base.calibrate(make_fdp(["9.3"], [target]), method=method, alignment=alignment)
    assert np.abs(face.mesh.fp("9.3") - target).max() <= 1e-9 * mesh.height()
    if alignment != "none" or method == "rbf":
        assert np.abs(face.mesh.vertices - (mesh.vertices + shift)).max() <= 1e-9 * mesh.height()
    else:  # a lone control of the DFFD: the point moves, the far head stays
        assert face.calibration.folded_triangles == 0
        assert np.abs(face.mesh.fp("11.6") - mesh.fp("11.6")).max() < np.linalg.norm(shift)


def test_calibrated_face_animates_with_its_own_fapu(procedural_face):
    mesh = procedural_face.mesh
    labels = mesh.fp_labels
    face = procedural_face.calibrate(make_fdp(labels, _targets(procedural_face, labels, smooth_map(mesh))))
    values = np.zeros(68)
    values[5 - 1] = 300  # raise_b_midlip: 2.3 up by 300 MNS
    moved = face.deform(values).feature_points - face.mesh.feature_points()
    assert moved[mesh.fp_index("2.3")] == pytest.approx([0, 300 * face.fapu.MNS0 / 1024, 0], abs=1e-9)


@pytest.mark.parametrize("labels,points,words", [
    (("2.1", "99.9"), np.zeros((2, 3)), "99.9"),
    (("2.1", "3.1"), np.array([[0.0, 0, 0], [np.nan, 0, 0]]), "finite"),
    (("2.1", "3.1"), np.array([[0.0, 0, 0], [np.inf, 0, 0]]), "finite"),
    (("2.1", "3.1"), np.zeros((3, 3)), "(n, 3)"),
    (("11.5",), np.zeros((1, 3)), "11.5"),
])
def test_bad_fdps_raise(procedural_face, labels, points, words):
    with pytest.raises(FaceError, match=None) as info:
        procedural_face.calibrate(StandIn(labels, points))
    assert words in str(info.value)
    with pytest.raises(FaceError):
        calibrate_mesh(procedural_face.mesh, labels, points)


@pytest.mark.parametrize("kwargs,words", [({"method": "spline"}, "spline"), ({"alignment": "affine"}, "affine")])
def test_unknown_method_or_alignment(procedural_face, kwargs, words):
    fdp = StandIn(("9.3",), procedural_face.mesh.fp("9.3")[None])
    with pytest.raises(FaceError) as info:
        procedural_face.calibrate(fdp, **kwargs)
    assert words in str(info.value)
