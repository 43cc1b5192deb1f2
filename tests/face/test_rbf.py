"""RBF displacement fields: interpolation, affine reproduction, kernels and bad input."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.rbf import KERNELS, RbfField
from mpeg4fa.face.sibson import cage_points


def controls_and_displacements(seed: int = 0, n: int = 60):
    rng = np.random.default_rng(seed)
    controls = rng.random((n, 3)) * [120.0, 160.0, 90.0] + [-60.0, 20.0, 500.0]  # millimetres, off-origin
    displacements = rng.normal(size=(n, 3)) * 2.0
    return controls, displacements


@pytest.mark.parametrize("kernel", sorted(KERNELS))
def test_exact_interpolation_at_controls(kernel):
    controls, disp = controls_and_displacements()
    degree = max(1, KERNELS[kernel])
    field = RbfField(controls, disp, kernel=kernel, degree=degree)
    spread = np.ptp(controls, axis=0).max()
    assert np.abs(field(controls) - disp).max() <= 1e-9 * spread
    out = field(np.random.default_rng(1).random((7, 3)) * 100)
    assert out.shape == (7, 3) and np.isfinite(out).all()


@pytest.mark.parametrize("kernel", sorted(KERNELS))
def test_affine_reproduction(kernel):
    rng = np.random.default_rng(2)
    controls, _ = controls_and_displacements(3, n=40)
    A = rng.normal(size=(3, 3)) * 0.05
    b = rng.normal(size=3)
    field = RbfField(controls, controls @ A.T + b, kernel=kernel, degree=max(1, KERNELS[kernel]))
    points = controls.min(0) - 30 + rng.random((500, 3)) * (np.ptp(controls, axis=0) + 60)  # inside and beyond
    scale = np.abs(points @ A.T + b).max()
    assert np.abs(field(points) - (points @ A.T + b)).max() <= 1e-8 * scale


def test_default_is_thin_plate_spline_degree_1():
    controls, disp = controls_and_displacements()
    field = RbfField(controls, disp)
    assert field.kernel == "thin_plate_spline" and field.degree == 1 and field.smoothing == 0.0
    assert "thin_plate_spline" in repr(field)


def test_smoothness_at_controls():
    # thin-plate spline: C^1 at a control; linear (-r): a kink (one-sided slopes differ)
    controls, disp = controls_and_displacements(4, n=30)
    p = controls[0]
    h = 1e-4 * np.ptp(controls, axis=0).max()
    probe = np.array([p - [h, 0, 0], p, p + [h, 0, 0]])
    for kernel, smooth in (("thin_plate_spline", True), ("cubic", True), ("linear", False)):
        f = RbfField(controls, disp, kernel=kernel)(probe)[:, 0]
        left, right = (f[1] - f[0]) / h, (f[2] - f[1]) / h
        kink = abs(right - left)
        assert (kink < 1e-2) == smooth, (kernel, kink)


def test_four_controls_give_the_affine_map():
    controls = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    disp = np.array([[0.1, 0, 0], [0.2, 0.1, 0], [0.1, 0.3, 0], [0.1, 0, -0.2]])
    for kernel in KERNELS:
        if KERNELS[kernel] > 1:
            continue
        field = RbfField(controls, disp, kernel=kernel)
        np.testing.assert_allclose(field(controls), disp, atol=1e-12)
        # affine: the value at the centroid is the mean
        np.testing.assert_allclose(field(controls.mean(0, keepdims=True))[0], disp.mean(0), atol=1e-12)


def test_scalar_and_vector_values():
    controls, _ = controls_and_displacements(5, n=20)
    values = np.arange(20.0)
    field = RbfField(controls, values)
    assert field(controls[:3]).shape == (3,)
    np.testing.assert_allclose(field(controls), values, atol=1e-9)
    assert field(np.empty((0, 3))).shape == (0,)
    wide = np.random.default_rng(6).random((20, 5))
    assert RbfField(controls, wide)(controls[:2]).shape == (2, 5)


def test_smoothing_approximates():
    controls, disp = controls_and_displacements(7)
    exact = RbfField(controls, disp)
    smooth = RbfField(controls, disp, smoothing=10.0)
    err = np.abs(smooth(controls) - disp).max()
    assert err > 1e-6  # no longer interpolates
    assert err < np.abs(disp).max()
    per_control = RbfField(controls, disp, smoothing=np.zeros(len(controls)))
    np.testing.assert_allclose(per_control(controls), exact(controls), atol=1e-9)


def test_with_cage_zero_displacement():
    controls, disp = controls_and_displacements(8, n=30)
    cage = cage_points(controls)
    field = RbfField(np.vstack([controls, cage]), np.vstack([disp, np.zeros((14, 3))]))
    np.testing.assert_allclose(field(cage), 0.0, atol=1e-9)


# -- bad input ----------------------------------------------------------------------------------


def test_too_few_controls_for_degree():
    controls = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    with pytest.raises(FaceError, match="3 control") as err:
        RbfField(controls, np.zeros((3, 3)))
    assert "at least 4" in err.value.hint
    # degree 0 with the linear kernel is allowed for so few controls
    field = RbfField(controls, np.ones((3, 3)), kernel="linear", degree=0)
    np.testing.assert_allclose(field(controls), 1.0, atol=1e-12)
    with pytest.raises(FaceError, match="10 terms"):
        RbfField(np.random.default_rng(0).random((9, 3)), np.zeros((9, 3)), kernel="quintic", degree=2)


def test_coplanar_controls_for_degree_1():
    rng = np.random.default_rng(9)
    controls = np.c_[rng.random((12, 2)), np.full(12, 3.0)]
    with pytest.raises(FaceError, match="one plane") as err:
        RbfField(controls, np.zeros((12, 3)))
    assert "cage_points" in err.value.hint


def test_degree_below_kernel_minimum():
    controls, disp = controls_and_displacements()
    with pytest.raises(FaceError, match="degree >= 1"):
        RbfField(controls, disp, kernel="thin_plate_spline", degree=0)
    with pytest.raises(FaceError, match="degree >= 2"):
        RbfField(controls, disp, kernel="quintic", degree=1)
    with pytest.raises(FaceError, match="integer"):
        RbfField(controls, disp, degree=1.5)


def test_duplicate_controls_named():
    controls, disp = controls_and_displacements(10, n=20)
    controls = np.vstack([controls, controls[4], controls[11] + 1e-12])
    disp = np.vstack([disp, disp[:2]])
    with pytest.raises(FaceError) as err:
        RbfField(controls, disp)
    text = str(err.value)
    assert "2 pair(s)" in text and "4 and 20" in text and "11 and 21" in text


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"kernel": "gaussian"}, "unknown kernel"),
        ({"smoothing": -1.0}, "smoothing"),
        ({"smoothing": np.ones(3)}, "one per control"),
    ],
)
def test_bad_options(kwargs, match):
    controls, disp = controls_and_displacements()
    with pytest.raises(FaceError, match=match):
        RbfField(controls, disp, **kwargs)


def test_bad_arrays():
    controls, disp = controls_and_displacements()
    with pytest.raises(FaceError, match="shape"):
        RbfField(controls[:, :2], disp)
    with pytest.raises(FaceError, match="one row per control"):
        RbfField(controls, disp[:-1])
    bad = disp.copy()
    bad[5, 1] = np.nan
    with pytest.raises(FaceError, match="first control 5"):
        RbfField(controls, bad)
    bad = controls.copy()
    bad[7, 0] = np.inf
    with pytest.raises(FaceError, match="index 7"):
        RbfField(bad, disp)
    with pytest.raises(FaceError, match="no controls"):
        RbfField(np.empty((0, 3)), np.empty((0, 3)), kernel="linear", degree=0)
    field = RbfField(controls, disp)
    with pytest.raises(FaceError, match="shape"):
        field(np.zeros(3))
