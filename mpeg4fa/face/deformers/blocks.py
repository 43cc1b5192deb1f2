"""Block elastic deformation: the eyes' and the mouth's skin move as linear (affine) fields.

The feature-point deformer spreads each feature point's motion by its own smooth
weight. This deformer splits the face into **blocks** (``data/blocks.csv``: each
eye region and the mouth region) whose skin moves by one displacement field that
is linear in the coordinates, the 12 physical parameters of an elastic block
about its reference point ``x0``::

    u(x) = t + (W + E) (x - x0)

* ``t = (u0, v0, w0)``: the rigid translation of the reference point;
* ``W``: the small rotation, antisymmetric, ``W r = (rx, ry, rz) x r`` (``rx`` turns
  in the y-z plane, about x; ``ry`` in the z-x plane; ``rz`` in the x-y plane);
* ``E``: the strain, symmetric: the normal strains ``ex, ey, ez`` on its diagonal
  and the **engineering** shear strains ``txy = 2 E_xy``, ``txz = 2 E_xz``,
  ``tyz = 2 E_yz`` off it (a pure ``txy`` changes the right angle between x and y
  by ``txy`` radians).

Per frame the parameters are the **least-squares fit** to the displacements that
the feature-point deformer gives the block's reference feature points (their
translational skin motion: what ``rig.weights @ fp_motion`` gives their vertices,
their own FAP motion for the points FAPs drive, the skin's for the passive outer
lid points). The fit is linear in those displacements, and they are linear in
the FAP values, so it is set up once per face: about the points' centroid ``c``
the field's gradient is ``M^T = pinv(R) U`` (``R`` the centred points, ``U`` their
displacements; the three components decouple) and ``t(c)`` is the mean of ``U``.
Every block vertex's displacement is therefore a fixed combination of the
feature point motions, with the same scalar coefficients for x, y and z: the
block only changes rows of the skin weight matrix and the frame costs what the
feature-point deformer's costs.

**Nearly coplanar points.** A unique fit needs at least 4 points not in one
plane. Where the smallest singular value of ``R`` is under :data:`COPLANAR`
times the largest, its inverse ``1/s`` is replaced by ``s / tau**2`` (``tau`` the
threshold; continuous at ``tau``, 0 for ``s = 0``): the field then does not vary
in the direction the points do not span (zero strain there) instead of
amplifying noise. The blocks of the generic head are far from that
(smallest / largest 0.25 for the eyes, 0.13-0.14 for the lips) and are solved exactly.

**What the block replaces, and what it keeps.** Only the translational skin
motion (the ``rig.weights_moving @ fp_motion`` step of
:func:`.feature_points.pose_in_head_frame`) and only on skin vertices: with a
block's weight ``w`` (1 inside, 0 outside), a vertex moves by
``w * block + (1 - w) * fap``, so the field blends into the feature-point
deformer's with no seam (both are continuous, the weight is a smooth function of
surface distance). Past the box of its points (their extent in x, y and z) a block's
field is held at its value on the box (:func:`held_offsets`): a linear field
extrapolated above the brows would raise the forehead more than the brows and fold
the skin where it meets the feature-point deformer's. The jaw, the lids, the eyeballs, the tongue and the head turn
afterwards exactly as in the feature-point deformer (same code, same order), so
FAPs 3, 14, 15, 19-30, 43-50 are exact. A block's weight is 1 within ``core_mm``
of surface distance of its points and falls to 0 over ``band_mm`` (20 mm: the mesh's
edges there are 3-9 mm long, a shorter band steps; the eyes' core is 0, a larger one folds
the skin above a brow raised to twice its largest used value, the lips' 5 mm); it is also
faded to 0 within ``clear_mm`` of every skin feature point the block does not
contain (they stay where their own FAPs put them: the nose, the chin, the other
eye) and within :data:`~mpeg4fa.face.rig.LID_CLEAR_MM` of the lid margins (they
belong to the lids, and must stay on the eyeball).

**What it realises approximately.** A linear field cannot give each of a
block's points an independent motion: a FAP that moves one point of a block
(``lower_t_midlip`` moves 2.2 alone) becomes the field nearest to it, which
moves that point by part of its FAPU motion and the block's other points a
little. :data:`FAP_ERRORS` lists, per FAP that has a point in a block, the
relative error of its feature point's motion (``|moved - value x FAPU x
direction| / (value x FAPU)``) on the generic head; every other FAP is exact.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass, replace
from functools import lru_cache
from importlib import resources
from typing import Sequence

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face.couplings import PASSIVE_POINTS
from mpeg4fa.face.deformers.feature_points import FoldGuard, deform, skin_guard
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.regions import LID_MARGIN_LOOPS, edge_graph, shortest_loop, smooth_down
from mpeg4fa.face.rig import LID_CLEAR_MM, Rig

PARAMETERS = ("u0", "v0", "w0", "rx", "ry", "rz", "ex", "ey", "ez", "txy", "txz", "tyz")
"""The 12 block parameters, in the order of every parameter vector here."""
COPLANAR = 0.02  # singular values of the centred points under this fraction of the largest are damped
REGIONS = ("eye_l", "eye_r", "lip_t", "lip_b")
"""The default blocks: each eye region, the upper and the lower lip (``"mouth"``, one block for
both lips, is the other choice for the mouth: one linear field cannot close the lips for PP
nor tuck the lower lip under the teeth for FF, and it realises the single-point lip FAPs
worse, e.g. FAP 4 with 0.91 of its motion missing instead of 0.51)."""

FAP_ERRORS: dict[int, tuple[float, float]] = {
    4: (0.51, 0.32), 5: (0.60, 0.35), 6: (0.57, 0.43), 7: (0.57, 0.43), 8: (0.71, 0.32), 9: (0.71, 0.32),
    10: (0.67, 0.35), 11: (0.67, 0.35), 12: (0.57, 0.43), 13: (0.57, 0.43), 16: (0.07, 0.03), 17: (0.04, 0.35),
    31: (0.34, 0.32), 32: (0.34, 0.32), 33: (0.56, 0.41), 34: (0.56, 0.41), 35: (0.42, 0.30), 36: (0.42, 0.30),
    37: (0.34, 0.32), 38: (0.34, 0.32), 39: (0.0, 0.0002), 40: (0.0, 0.0002), 41: (0.0001, 0.06),
    42: (0.0001, 0.06), 51: (0.78, 0.19), 52: (0.58, 0.34), 53: (0.58, 0.43), 54: (0.58, 0.43), 55: (0.75, 0.25),
    56: (0.75, 0.25), 57: (0.65, 0.34), 58: (0.65, 0.34), 59: (0.58, 0.43), 60: (0.58, 0.43),
    61: (0.0, 0.0011), 62: (0.0, 0.0011),
}
"""The FAPs this deformer realises approximately, with the default blocks on the generic head,
each alone at +-200 (the errors are linear in the value, so the same at any value): FAP ->
(error of its own feature point's motion, worst motion of any other feature point away from
where the feature-point deformer puts it), both relative to value x FAPU and rounded up to
0.01 (0.0001 under 0.005). 39-42 (cheek puff and lift) move their point as the feature-point
deformer does (41/42 0.0001 off FAPU in both), but the passive outer lid centre 3.9/3.10 that
rides on that skin moves with the eye block's field instead; so does it under 61/62 (nose stretch) at -200,
where the feature-point deformer's fold guard spreads a little (0.01 mm). Every FAP not listed is
exact (to rounding): the jaw, lids, eyes, tongue, head, nose, ears, cheek puff, chin."""


# ---------------------------------------------------------------- the 12-parameter field


def field_from_parameters(params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(t, M)``: the translation (3,) and the displacement gradient ``M = W + E`` (3, 3)."""
    p = np.asarray(params, dtype=np.float64)
    u0, v0, w0, rx, ry, rz, ex, ey, ez, txy, txz, tyz = p
    m = np.array([[ex, txy / 2 - rz, txz / 2 + ry],
                  [txy / 2 + rz, ey, tyz / 2 - rx],
                  [txz / 2 - ry, tyz / 2 + rx, ez]])
    return np.array([u0, v0, w0]), m


def parameters_from_field(t: np.ndarray, m: np.ndarray) -> np.ndarray:
    """The 12 parameters of the field ``t + M (x - x0)`` (inverse of :func:`field_from_parameters`)."""
    m = np.asarray(m, dtype=np.float64)
    w = 0.5 * (m - m.T)
    e = 0.5 * (m + m.T)
    return np.array([*np.asarray(t, dtype=np.float64), w[2, 1], w[0, 2], w[1, 0],
                     e[0, 0], e[1, 1], e[2, 2], 2 * e[0, 1], 2 * e[0, 2], 2 * e[1, 2]])


def design_matrix(points: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``(3n, 12)``: parameters -> displacements of ``points`` (x, y, z of each point in turn)."""
    r = np.asarray(points, dtype=np.float64) - np.asarray(reference, dtype=np.float64)
    a = np.zeros((len(r), 3, 12))
    for k in range(12):
        unit = np.zeros(12)
        unit[k] = 1.0
        t, m = field_from_parameters(unit)
        a[:, :, k] = t + r @ m.T
    return a.reshape(-1, 12)


def displacement(params: np.ndarray, points: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``(n, 3)``: the block field of ``params`` at ``points``."""
    t, m = field_from_parameters(params)
    return t + (np.asarray(points, dtype=np.float64) - reference) @ m.T


def fit_operator(points: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``(4, n)`` ``H``: point displacements ``U (n, 3)`` -> ``H @ U = [t; M^T]``, the least-squares
    field about ``reference`` (row 0 its translation, rows 1-3 the transposed gradient).

    Least squares over the points, solved about their centroid (where translation and
    gradient decouple); singular values of the centred points under :data:`COPLANAR` x the
    largest are damped (see the module's docstring)."""
    p = np.asarray(points, dtype=np.float64)
    if len(p) < 4:
        raise FaceError(f"a block needs at least 4 points for its 12 parameters, got {len(p)}",
                        hint="add feature points to the block in data/blocks.csv")
    c = p.mean(axis=0)
    u, s, vt = np.linalg.svd(p - c, full_matrices=False)  # (n,3) (3,) (3,3)
    tau = COPLANAR * s[0]
    inv = np.where(s >= tau, 1.0 / np.where(s > 0, s, 1.0), s / tau ** 2)
    gradient_t = (vt.T * inv) @ u.T  # (3, n): M^T = pinv(R) U
    translation = np.full(len(p), 1.0 / len(p)) + (np.asarray(reference, float) - c) @ gradient_t
    return np.vstack([translation, gradient_t])


def solve_parameters(points: np.ndarray, reference: np.ndarray, displacements: np.ndarray) -> np.ndarray:
    """The 12 parameters (``(..., 12)``) of the least-squares field through ``displacements``
    (``(..., n, 3)``) of ``points`` about ``reference``."""
    h = fit_operator(points, reference)
    field = np.einsum("kn,...nj->...kj", h, np.asarray(displacements, dtype=np.float64))
    flat = field.reshape(-1, 4, 3)
    out = np.array([parameters_from_field(f[0], f[1:].T) for f in flat])
    return out.reshape(field.shape[:-2] + (12,))


# ---------------------------------------------------------------- blocks on a face


@dataclass(frozen=True)
class BlockSpec:
    """One row of ``data/blocks.csv``."""

    name: str
    points: tuple[str, ...]
    reference: tuple[str, ...]  # the reference point is the mean of these feature points
    core_mm: float
    band_mm: float
    clear_mm: float
    instead_of: tuple[str, ...] = ()  # blocks this one cannot be combined with (the same skin)


@lru_cache(maxsize=1)
def block_specs() -> dict[str, BlockSpec]:
    """The blocks of ``data/blocks.csv``, by name."""
    with (resources.files("mpeg4fa.face") / "data" / "blocks.csv").open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return {r["block"]: BlockSpec(r["block"], tuple(r["points"].split()), tuple(r["reference"].split()),
                                  float(r["core_mm"]), float(r["band_mm"]), float(r["clear_mm"]),
                                  tuple(r["instead_of"].split())) for r in rows}


@dataclass(frozen=True)
class Block:
    """One block set up on one face."""

    name: str
    labels: tuple[str, ...]
    fp: np.ndarray  # feature point indices of its reference points
    reference: np.ndarray  # (3,) x0
    rows: np.ndarray  # skin vertices it moves (weight > 0)
    weight: np.ndarray  # their block weight in (0, 1]
    fit: np.ndarray  # (4, n) least-squares operator (:func:`fit_operator`)
    box: tuple[np.ndarray, np.ndarray]  # the points' extent in x, y, z, about the reference point
    targets: sp.csr_matrix  # (n, 84): feature point motion -> the points' translational displacement


def _surface_distance(graph: sp.csr_matrix, sources: np.ndarray, limit: float) -> np.ndarray:
    if len(sources) == 0:
        return np.full(graph.shape[0], np.inf)
    return dijkstra(graph, indices=np.unique(sources), min_only=True, limit=limit)


def build_block(mesh: HeadMesh, rig: Rig, spec: BlockSpec, graph: sp.csr_matrix | None = None,
                margins: np.ndarray | None = None) -> Block:
    """Set up block ``spec`` on ``mesh``: its points, reference, fit and smooth weight.

    ``graph`` (the skin's edge graph over all vertices) and ``margins`` (the lid margin
    vertices) are shared by the blocks of one face; computed here when not given."""
    skin = mesh.part("skin")
    graph = edge_graph(mesh.vertices, mesh.triangles["skin"]) if graph is None else graph
    if margins is None:
        margins = np.concatenate([shortest_loop(mesh, loop, graph) for loop in LID_MARGIN_LOOPS])
    try:
        fp = np.array([mesh.fp_index(label) for label in spec.points])
        ref = np.mean([mesh.fp(label) for label in spec.reference], axis=0)
    except FaceError as e:
        raise FaceError(f"block {spec.name}: {e.message}", hint="see face/data/blocks.csv") from None
    vertex = mesh.fp_vertex[fp]
    if not np.all((vertex >= skin.start) & (vertex < skin.stop)):
        raise FaceError(f"block {spec.name}: every point must be on the skin", hint="see face/data/blocks.csv")
    own = _surface_distance(graph, vertex, spec.core_mm + spec.band_mm)
    w = smooth_down((own - spec.core_mm) / spec.band_mm)
    mine = set(vertex.tolist())
    foreign = np.array([int(v) for i, v in enumerate(mesh.fp_vertex)
                        if skin.start <= v < skin.stop and int(v) not in mine
                        and mesh.fp_labels[i] not in PASSIVE_POINTS], dtype=np.int64)
    w *= 1.0 - smooth_down(_surface_distance(graph, foreign, spec.clear_mm) / spec.clear_mm)
    w *= 1.0 - smooth_down(_surface_distance(graph, margins, LID_CLEAR_MM) / LID_CLEAR_MM)
    w[:skin.start] = 0.0
    w[skin.stop:] = 0.0
    rows = np.flatnonzero(w > 0)
    points = mesh.vertices[vertex]
    return Block(name=spec.name, labels=spec.points, fp=fp, reference=ref, rows=rows, weight=w[rows],
                 fit=fit_operator(points, ref), box=((points - ref).min(axis=0), (points - ref).max(axis=0)),
                 targets=rig.weights[vertex].tocsr())


def held_offsets(block: Block, x: np.ndarray) -> np.ndarray:
    """``x - x0`` with each coordinate (x, y, z) held to the block points' extent: the field is
    linear over the box of its points and constant beyond it (a linear field extrapolated past
    the brows raises the forehead more than the brows, and pushes the back of the mouth bag)."""
    return np.clip(np.asarray(x, dtype=np.float64) - block.reference, block.box[0], block.box[1])


def block_weights(rig: Rig, blocks: Sequence[Block]) -> sp.csr_matrix:
    """``(V, 84)`` skin weights with the blocks in: ``w * field + (1 - w) * fap`` on each block's rows.

    A block row's field coefficients are ``[1, x - x0] @ fit @ targets`` (``x - x0`` held to the
    points' extent, :func:`held_offsets`): one scalar per feature point, the same for x, y and z
    (the least-squares fit decouples by component). Where blocks overlap (the lip corners, which
    both lips contain) their weights are scaled to sum to 1."""
    n_v = rig.rest.shape[0]
    share = np.zeros(n_v)
    for b in blocks:
        share[b.rows] += b.weight
    scale = np.where(share > 1.0, 1.0 / np.maximum(share, 1e-300), 1.0)  # overlapping blocks share a vertex
    keep = sp.diags(1.0 - share * scale)
    out = keep @ rig.weights
    for b in blocks:
        basis = np.hstack([np.ones((len(b.rows), 1)), held_offsets(b, rig.rest[b.rows])])  # (r, 4)
        coeff = (basis @ b.fit) @ b.targets  # (r, 84), dense in the block's points
        coeff = sp.csr_matrix(np.asarray(coeff) * (b.weight * scale[b.rows])[:, None])
        out = out + _place(coeff, b.rows, n_v)
    out = out.tocsr()
    out.eliminate_zeros()
    return out


def _place(m: sp.csr_matrix, rows: np.ndarray, n_rows: int) -> sp.csr_matrix:
    coo = m.tocoo()
    return sp.csr_matrix((coo.data, (rows[coo.row], coo.col)), shape=(n_rows, m.shape[1]))


@dataclass(frozen=True)
class BlocksDeformer:
    """The block deformer set up for one face: ``values (68,) -> Pose``.

    ``block_rig`` is the face's rig with the blocks' skin weights in; ``blocks`` the blocks; ``guard``
    the feature-point deformer's fold guard over those weights (the skin outside the blocks folds no more
    than it does there)."""

    rig: Rig
    block_rig: Rig
    blocks: tuple[Block, ...]
    guard: FoldGuard | None = None

    def __call__(self, values: np.ndarray) -> Pose:
        return deform(self.block_rig, values, self.guard)

    def parameters(self, values: np.ndarray) -> dict[str, np.ndarray]:
        """Each block's 12 parameters (:data:`PARAMETERS`) for one frame of FAP values: the field of
        the translational skin motion, in the head's frame before the jaw and head turn (FAP 3
        opens the jaw by rotation: it changes no block's parameters)."""
        fp_motion = (self.rig.translate @ np.asarray(values, dtype=np.float64)).reshape(-1, 3)
        out = {}
        for b in self.blocks:
            field = b.fit @ (b.targets @ fp_motion)
            out[b.name] = parameters_from_field(field[0], field[1:].T)
        return out


def check_options(regions: Sequence[str] | str = REGIONS) -> tuple[str, ...]:
    """``regions`` as a tuple of known, compatible block names (one name may be given as a string)."""
    if isinstance(regions, str):
        regions = (regions,)
    if not isinstance(regions, (tuple, list)) or not all(isinstance(r, str) for r in regions):
        raise FaceError(f"regions={regions!r} is not a list of block names", hint=f"names from {', '.join(REGIONS)}")
    specs = block_specs()
    unknown = [r for r in regions if r not in specs]
    if unknown:
        raise FaceError(f"unknown block {unknown[0]!r}", hint=f"one of {', '.join(specs)}")
    for r in regions:
        clash = [o for o in specs[r].instead_of if o in regions]
        if clash:
            raise FaceError(f"blocks {r!r} and {clash[0]!r} cover the same skin", hint="choose one of them")
    return tuple(regions)


def blocks_deformer(mesh: HeadMesh, rig: Rig, regions: Sequence[str] = REGIONS) -> BlocksDeformer:
    """The block deformer with only the blocks ``regions`` (names of ``data/blocks.csv``) active;
    elsewhere the face moves as with the feature-point deformer (``regions=()``: exactly it)."""
    regions = check_options(regions)
    specs = block_specs()
    graph = edge_graph(mesh.vertices, mesh.triangles["skin"])
    margins = np.concatenate([shortest_loop(mesh, loop, graph) for loop in LID_MARGIN_LOOPS])
    blocks = tuple(build_block(mesh, rig, specs[r], graph, margins) for r in dict.fromkeys(regions))
    weights = block_weights(rig, blocks)
    moving = np.unique(weights.nonzero()[0])
    block_rig = replace(rig, weights=weights, moving=moving, weights_moving=weights[moving])
    return BlocksDeformer(rig=rig, block_rig=block_rig, blocks=blocks, guard=skin_guard(mesh, block_rig))


def build(mesh: HeadMesh, rig: Rig, regions: Sequence[str] = REGIONS) -> BlocksDeformer:
    """The deformer as the registry builds it: the blocks ``regions`` (all of :data:`REGIONS` by default)."""
    return blocks_deformer(mesh, rig, regions)
