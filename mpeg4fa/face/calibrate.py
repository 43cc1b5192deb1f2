"""Fit the generic head to the feature points a sender transmitted (FDP calibration).

Two steps, both over plain arrays:

1. **Global alignment** of the head's feature points onto the received ones:
   ``similarity`` (least-squares scale + rotation + translation, Umeyama's method;
   the default), ``bbox`` (per-axis scale and shift that map the bounding boxes) or
   ``none``. With fewer than 3 points only a translation (and, for 2, a scale).
2. **Residual warp** that puts every received point exactly in place and carries
   the rest of the mesh along smoothly:

   * ``dffd`` (default): Dirichlet free-form deformation. Every vertex moves by
     sum_i u_i(x) dp_i, u_i its Sibson coordinates with respect to the control
     points (the aligned feature points). Sibson coordinates exist only inside
     the control points' convex hull, so a cage of 14 extra controls around the
     whole head, with zero displacement, is added: vertices outside the feature
     points' hull (the back of the skull, the neck) keep the global alignment.
   * ``rbf``: a polyharmonic radial-basis field through the same displacements
     (see :mod:`mpeg4fa.face.rbf`), no cage needed (its affine part extrapolates).
   * ``elastic``: not a field in space but an elastic skin (thin plate on an elastic
     foundation, one sparse solve, see :mod:`mpeg4fa.face.elastic`): the residuals are
     imposed on the feature points' vertices and the mesh follows along its surface.
     It reshapes the head it was shaped from, so moving the points back restores it.

The eyeballs are rigid: each moves with its pupil's displacement (or with the
warp at its centre when no pupil was sent). 11.5 (hair thickness) is not a skin
point on a bald head and is not used as a control.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.sibson import cage_points, natural_neighbour_weights

METHODS = ("dffd", "rbf", "elastic")
ALIGNMENTS = ("similarity", "bbox", "none")
NOT_CONTROLS = ("11.5",)
_EYES = {"3.5": ("eye_l", "l-eye"), "3.6": ("eye_r", "r-eye")}


@dataclass(frozen=True)
class CalibrationReport:
    """What a calibration did, with the numbers that say whether it went well."""

    method: str
    alignment: str
    labels: tuple[str, ...]  # the feature points used as controls
    scale: float  # global scale of the alignment
    max_error: float  # largest |model point - received point| after calibration (model units)
    max_error_relative: float  # the same divided by the head height
    min_quality_before: float  # worst triangle quality of the skin (1 = equilateral)
    min_quality_after: float
    folded_triangles: int  # skin triangles whose normal turned by more than 90 degrees
    seconds: float

    def as_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


def similarity_fit(src: np.ndarray, dst: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Scale, rotation and translation minimising |s R src + t - dst|^2 (no reflection)."""
    n = len(src)
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    if n == 1:
        return 1.0, np.eye(3), mu_d - mu_s
    a, b = src - mu_s, dst - mu_d
    var = (a ** 2).sum() / n
    if n == 2 or np.linalg.matrix_rank(a, tol=1e-9 * max(np.abs(a).max(), 1.0)) < 2:
        scale = np.sqrt((b ** 2).sum() / n / var) if var > 0 else 1.0
        return scale, np.eye(3), mu_d - scale * mu_s
    u, sig, vt = np.linalg.svd(b.T @ a / n)
    d = np.ones(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        d[-1] = -1.0
    rot = u @ np.diag(d) @ vt
    scale = float((sig * d).sum() / var)
    return scale, rot, mu_d - scale * rot @ mu_s


def bbox_fit(src: np.ndarray, dst: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-axis scale and shift mapping the bounding box of ``src`` onto that of ``dst``."""
    lo_s, hi_s = src.min(axis=0), src.max(axis=0)
    lo_d, hi_d = dst.min(axis=0), dst.max(axis=0)
    span = hi_s - lo_s
    scale = np.where(span > 1e-9, (hi_d - lo_d) / np.where(span > 1e-9, span, 1.0), 1.0)
    if (span > 1e-9).any():  # a flat axis takes the mean scale of the others
        scale = np.where(span > 1e-9, scale, scale[span > 1e-9].mean())
    return scale, lo_d - scale * lo_s


def triangle_quality(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """4 sqrt(3) area / sum of squared edges: 1 for equilateral, 0 for degenerate."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    edges = ((b - a) ** 2).sum(1) + ((c - b) ** 2).sum(1) + ((a - c) ** 2).sum(1)
    return 4.0 * np.sqrt(3.0) * area / np.maximum(edges, 1e-300)


def _normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return np.cross(b - a, c - a)


def calibrate_mesh(mesh: HeadMesh, labels: tuple[str, ...], points: np.ndarray, *, method: str = "dffd",
                   alignment: str = "similarity") -> tuple[HeadMesh, CalibrationReport]:
    """The head deformed so that its feature points ``labels`` sit at ``points``."""
    if method not in METHODS:
        raise FaceError(f"unknown calibration method {method!r}", hint=f"one of {', '.join(METHODS)}")
    if alignment not in ALIGNMENTS:
        raise FaceError(f"unknown alignment {alignment!r}", hint=f"one of {', '.join(ALIGNMENTS)}")
    points = np.asarray(points, dtype=np.float64)
    if points.shape != (len(labels), 3) or not np.isfinite(points).all():
        raise FaceError(f"calibration needs finite (n, 3) points for {len(labels)} labels, got {points.shape}")
    use = [i for i, label in enumerate(labels) if label not in NOT_CONTROLS]
    if not use:
        raise FaceError("the FDP has no feature point the head can be calibrated to",
                        hint="send at least one of the 84 feature points (11.5 alone is not enough)")
    labels = tuple(labels[i] for i in use)
    target = points[use]
    started = time.perf_counter()
    if method == "elastic":  # shaping starts from the rest head: the result depends on the points only
        from mpeg4fa.face.elastic import rest_head

        mesh = rest_head(mesh)
    fp_rows = np.array([mesh.fp_index(label) for label in labels])
    fp_v = mesh.fp_vertex[fp_rows]
    rest = mesh.vertices
    source = rest[fp_v]

    scale = 1.0
    if alignment == "similarity":
        scale, rot, shift = similarity_fit(source, target)
        aligned = scale * rest @ rot.T + shift
    elif alignment == "bbox":
        axis_scale, shift = bbox_fit(source, target) if len(labels) > 1 else (np.ones(3), target[0] - source[0])
        aligned = rest * axis_scale + shift
        scale = float(np.cbrt(np.prod(axis_scale)))
    else:
        aligned = rest.copy()

    residual = target - aligned[fp_v]
    rigid = np.zeros(mesh.n_vertices, bool)
    for part, _ in _EYES.values():
        rigid[mesh.part(part)] = True
    free = np.flatnonzero(~rigid)
    warped = aligned.copy()
    if np.abs(residual).max() > 0 and method == "elastic":
        from mpeg4fa.face.elastic import elastic_displacement

        warped[free] += elastic_displacement(mesh, fp_v, residual)[free]
    elif np.abs(residual).max() > 0:
        warped[free] += _warp(method, aligned[fp_v], residual, aligned[free], aligned)
    for label, (part, joint) in _EYES.items():
        s = mesh.part(part)
        centre_before = aligned[mesh.joints[joint]]
        if label in labels:
            move = residual[labels.index(label)]
            warped[mesh.joints[joint]] = centre_before + move
        else:
            move = warped[mesh.joints[joint]] - centre_before
        warped[s] = aligned[s] + move

    tris = mesh.triangles["skin"]
    q_before = triangle_quality(rest, tris)
    q_after = triangle_quality(warped, tris)
    n0, n1 = _normals(rest, tris), _normals(warped, tris)
    folded = int((np.einsum("ij,ij->i", n0, n1) < 0).sum())
    if method == "elastic":
        from mpeg4fa.face.elastic import remember_rest

        calibrated = mesh.with_vertices(warped, calibrated_with=method, **remember_rest(mesh, warped))
    else:
        calibrated = mesh.with_vertices(warped, calibrated_with=method)
    error = np.linalg.norm(warped[fp_v] - target, axis=1).max()
    report = CalibrationReport(
        method=method, alignment=alignment, labels=labels, scale=float(scale), max_error=float(error),
        max_error_relative=float(error / max(calibrated.height(), 1e-12)),
        min_quality_before=float(q_before.min()), min_quality_after=float(q_after.min()),
        folded_triangles=folded, seconds=time.perf_counter() - started,
    )
    return calibrated, report


def _warp(method: str, controls: np.ndarray, displacement: np.ndarray, queries: np.ndarray,
          everything: np.ndarray) -> np.ndarray:
    """Displacement of ``queries`` interpolating ``displacement`` at ``controls``."""
    if method == "rbf":
        from mpeg4fa.face.rbf import RbfField  # scipy.interpolate loads only when asked for

        if len(controls) < 4:
            shift = displacement.mean(axis=0)
            return np.broadcast_to(shift, queries.shape).copy()
        return RbfField(controls, displacement)(queries)
    cage = cage_points(np.concatenate([everything, controls]))
    sites = np.concatenate([controls, cage])
    values = np.concatenate([displacement, np.zeros_like(cage)])
    weights = natural_neighbour_weights(sites, queries)
    return weights @ values
