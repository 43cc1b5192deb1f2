"""Radial-basis-function interpolation of control-point displacements.

:class:`RbfField` turns displacements ``dp_i`` known at control points ``p_i``
(MPEG-4 feature points, possibly plus a zero-displacement cage) into a smooth
displacement field on all of space, evaluated at mesh vertices.  It wraps
``scipy.interpolate.RBFInterpolator``::

    s(x) = sum_i w_i phi(|x - p_i|) + q(x),   q a polynomial of degree ``degree``

with ``s(p_i) = dp_i`` (``smoothing=0``) and the side conditions that make the
weights orthogonal to polynomials of that degree.

Kernel choice (3D)
------------------
Only the polyharmonic kernels are offered: they have no shape parameter, so the
field does not depend on the units or scale of the model.

* ``"linear"`` (``phi = -r``) is the biharmonic Green's function in 3D: the
  interpolant minimises the bending energy ``∫ |D^2 s|^2`` over R^3 (Bookstein's
  3D thin-plate spline).  But ``|x - p_i|`` has a conical kink at ``p_i``: the
  field is only C^0 at the control points, and MPEG-4 feature points sit on the
  skin, so every moved feature point would pull a small tent (a crease) into
  the mesh around it.
* ``"thin_plate_spline"`` (``phi = r^2 log r``, the 2D biharmonic kernel) is
  conditionally positive definite of order 2 in any dimension, so it is also
  well posed in 3D with ``degree >= 1``.  Its gradient ``r (2 log r + 1)``
  vanishes at ``r = 0``: the field is C^1 everywhere, the curvature only
  log-singular at the controls, which looks smooth on a mesh.  It is also the
  customary choice for feature-point driven face warping.  **Default**, with
  ``degree=1``.
* ``"cubic"`` (``phi = r^3``, the 3D triharmonic spline) is C^2 but more global:
  it overshoots more between and beyond sparse controls.
* ``"quintic"`` (``phi = -r^5``) needs ``degree >= 2``.

``degree=1`` (the default) adds an affine part, so an affine displacement (a
global rotation, scaling or shear of all controls) is reproduced exactly
everywhere, not just at the controls; every kernel here accepts it.  It needs at
least 4 controls not all in one plane (``degree=2``: 10 controls not on a
quadric).  With exactly 4 controls the field is the affine map through them.

``smoothing > 0`` trades exact interpolation for a smoother field (per control
when given as an array), useful for noisy tracked feature points.
"""
from __future__ import annotations

from itertools import product
from math import comb

import numpy as np
from scipy.interpolate import RBFInterpolator

from .errors import FaceError
from .points import as_points, reject_duplicates

__all__ = ["KERNELS", "RbfField"]

_WHERE = "RbfField"

#: Supported kernels and the least polynomial degree each needs (its order of
#: conditional positive definiteness minus one).
KERNELS: dict[str, int] = {"linear": 0, "thin_plate_spline": 1, "cubic": 1, "quintic": 2}

_DUPLICATE_TOL = 1e-9  # x bounding-box diagonal
_RANK_TOL = 1e-10


def _monomials(points: np.ndarray, degree: int) -> np.ndarray:
    """Monomials of total degree <= ``degree`` at ``points`` (n x comb(degree + 3, 3))."""
    powers = [e for e in product(range(degree + 1), repeat=3) if sum(e) <= degree]
    return np.stack([np.prod(points ** np.array(e), axis=1) for e in powers], axis=1)


class RbfField:
    """Displacement field interpolating ``displacements[i]`` at ``controls[i]``.

    ``controls`` is (n, 3); ``displacements`` is (n, 3) (or (n,) / (n, k) for
    other per-control values).  Calling the field with (m, 3) points returns the
    interpolated values, shaped (m, 3) (or (m,) / (m, k)).  See the module
    docstring for the kernels; bad input raises :class:`FaceError`.
    """

    def __init__(
        self,
        controls: np.ndarray,
        displacements: np.ndarray,
        *,
        kernel: str = "thin_plate_spline",
        smoothing: float | np.ndarray = 0.0,
        degree: int = 1,
    ) -> None:
        controls = as_points(controls, "controls", _WHERE)
        n = len(controls)
        values = np.asarray(displacements, dtype=float)
        if values.ndim not in (1, 2) or len(values) != n:
            raise FaceError(
                f"displacements must have shape ({n}, 3) (one row per control), not {values.shape}", where=_WHERE
            )
        if not np.isfinite(values).all():
            bad = np.flatnonzero(~np.isfinite(values.reshape(n, -1)).all(axis=1))
            raise FaceError(
                f"displacements of {len(bad)} control(s) are not finite, first control {bad[0]}", where=_WHERE
            )
        if kernel not in KERNELS:
            raise FaceError(
                f"unknown kernel {kernel!r}", where=_WHERE, hint=f"use one of {', '.join(sorted(KERNELS))}"
            )
        if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)):
            raise FaceError(f"degree must be an integer, not {degree!r}", where=_WHERE)
        degree = int(degree)
        least = KERNELS[kernel]
        if degree < least:
            raise FaceError(
                f"kernel {kernel!r} needs a polynomial part of degree >= {least}, got degree={degree}",
                where=_WHERE,
                hint=f"use degree={max(least, 1)} (1 also reproduces affine motion exactly)",
            )
        smooth = np.asarray(smoothing, dtype=float)
        if smooth.ndim not in (0, 1) or (smooth.ndim == 1 and len(smooth) != n):
            raise FaceError(
                f"smoothing must be a number or one per control ({n}), not shape {smooth.shape}", where=_WHERE
            )
        if not (np.isfinite(smooth).all() and (smooth >= 0).all()):
            raise FaceError(f"smoothing must be finite and >= 0, got {smoothing!r}", where=_WHERE)
        if n == 0:
            raise FaceError("no controls given", where=_WHERE)

        lo, hi = controls.min(axis=0), controls.max(axis=0)
        diag = float(np.linalg.norm(hi - lo))
        reject_duplicates(controls, _DUPLICATE_TOL * diag, "controls", _WHERE,
                          "merge duplicate control points (their displacements may conflict)")
        terms = comb(degree + 3, 3)
        if n < terms:
            raise FaceError(
                f"{n} control(s) cannot determine a degree-{degree} polynomial part ({terms} terms)",
                where=_WHERE,
                hint=f"add controls (at least {terms}) or lower the degree (kernel {kernel!r} allows >= {least})",
            )
        if degree >= 1:
            scale = float((hi - lo).max())
            sv = np.linalg.svd(_monomials((controls - (lo + hi) / 2) / scale, degree), compute_uv=False)
            if sv[-1] <= _RANK_TOL * sv[0]:
                shape = {1: "all lie in one plane", 2: "all lie on one quadric surface"}.get(
                    degree, f"do not determine a degree-{degree} polynomial"
                )
                raise FaceError(
                    f"the {n} controls {shape}: the degree-{degree} part of the field is undetermined",
                    where=_WHERE,
                    hint="add a control off that surface (e.g. cage_points) or lower the degree",
                )
        try:
            self._interp = RBFInterpolator(controls, values, smoothing=smooth, kernel=kernel, degree=degree)
        except (np.linalg.LinAlgError, ValueError) as exc:
            raise FaceError(f"the RBF system cannot be solved: {exc}", where=_WHERE) from None
        self.controls = controls.copy()
        self.controls.flags.writeable = False
        self.displacements = values.copy()
        self.displacements.flags.writeable = False
        self.kernel = kernel
        self.degree = degree
        self.smoothing = smooth.copy() if smooth.ndim else float(smooth)

    def __call__(self, points: np.ndarray) -> np.ndarray:
        """The field at ``points`` (m, 3)."""
        pts = as_points(points, "points", _WHERE)
        if len(pts) == 0:
            return np.zeros((0,) + self.displacements.shape[1:])
        return self._interp(pts)

    def __repr__(self) -> str:
        return (
            f"RbfField({len(self.controls)} controls, kernel={self.kernel!r}, degree={self.degree}, "
            f"smoothing={self.smoothing!r})"
        )
