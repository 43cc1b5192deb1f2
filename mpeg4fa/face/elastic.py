"""Linear elastic shaping: feature points drag the head's vertices through an elastic skin.

The third calibration method (``calibrate(fdp, method="elastic")``, beside the
spatial warps DFFD and RBF): after the global alignment, the residual
displacement of each sent feature point is imposed on its vertex and the rest of
the mesh follows as a thin elastic plate glued to an elastic foundation. The
displacement ``d`` (each coordinate on its own) minimises

    E(d) = d' L M^-1 L d  +  (MEMBRANE / h^2) d' L d  +  (FOUNDATION / h^4) d' M d

with ``L`` the cotangent Laplacian of the part's triangles (the finite-element
stiffness of the piecewise-linear surface), ``M`` the lumped vertex areas and
``h`` the head height. The first term is bending (a discrete thin plate: it
keeps the field C^1 at a constrained vertex, where a membrane alone would pull a
tent), the second a little tension, the third a foundation that ties every
vertex to the aligned head, so that far from any control (the back of the
skull, the neck) the displacement dies away over ``h / FOUNDATION^(1/4)`` and
the head keeps the global alignment. Every term is invariant under a
similarity of the mesh, so the field does not depend on units or on the
alignment. Constrained vertices are eliminated; the free block is factorised
once per mesh and control set (cached), after which any displacement of the
controls is a matrix product: the map from control displacements to vertex
displacements is linear and fixed, so moving the points back (zero residual)
returns every vertex exactly.

**Parts.** The skin is the elastic body. The eyeballs are rigid (the caller,
:mod:`mpeg4fa.face.calibrate`, moves them with their pupils). Teeth and tongue
are carried by the skin (each vertex moves with an inverse-distance average of
the skin's displacement, area-weighted, power 4, so they move with the lips and
jaw next to them and stay inside the mouth; each part takes the best affine fit of
that over its vertices, so that it keeps its shape). When their own feature points
(9.8-9.11, 6.1-6.4) were sent, what those still lack is fitted by one affine map
shared by teeth and tongue (least squares; a translation for one point), so the
tongue's sides also set the width of the teeth beside them, and then an elastic
solve of the same energy over each part's own triangles adds what puts its
points exactly in place. Joint centres (no triangles) move
with the same kind of average of the meshed vertices around them, except that a
joint which is a sent feature point (7.1) takes its residual exactly.

**Rest shape.** A head calibrated this way remembers the head it was shaped
from (:func:`rest_head`): calibrating it again with ``method="elastic"``
reshapes that rest head, so the result depends only on the points sent and
moving them back restores the original head to rounding (path independence,
which a re-linearisation about the deformed head would not have).
"""
from __future__ import annotations

import hashlib
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh

__all__ = ["MEMBRANE", "FOUNDATION", "ElasticBody", "ElasticModel", "cotan_laplacian", "stiffness", "elastic_model",
           "elastic_displacement", "rest_head", "remember_rest"]

MEMBRANE = 0.0
"""Tension relative to bending (dimensionless, times 1/h^2)."""
FOUNDATION = 1000.0
"""Foundation stiffness relative to bending (dimensionless, times 1/h^4): length h / 1000^(1/4) = 0.18 h (41 mm
on the generic head), about the size of a facial region. With only the lips sent and no global fit, what is
0.6 h away from them moves by under 5 % of the lips' displacement (1000: 4 %; 300: 20 %; 3000: 3.5 %), while
the worst triangle quality on realistic FDPs hardly changes between 100 and 3000."""
CARRIED = ("teeth_upper", "teeth_lower", "tongue")
"""Parts the skin carries, each also an elastic body of its own for its feature points."""
_IDW_POWER = 4.0
_IDW_SOFT = 0.03  # x head height: keeps the average finite and smooth near the skin
_CACHE_SIZE = 4
_INFO_KEY = "elastic_rest"
_ORDERING = "COLAMD"  # column order for the sparse LU (fastest here of those SuperLU offers)


def cotan_laplacian(vertices: np.ndarray, triangles: np.ndarray, n: int) -> tuple[sp.csr_matrix, np.ndarray]:
    """``(L, mass)``: the cotangent Laplacian (positive semidefinite, rows sum to 0) and lumped vertex areas.

    ``L`` is the stiffness matrix of linear finite elements on the triangles, so it is
    positive semidefinite even where obtuse angles give negative weights.
    """
    tri = np.asarray(triangles, dtype=np.int64)
    p = [vertices[tri[:, k]] for k in range(3)]
    cross = np.cross(p[1] - p[0], p[2] - p[0])
    double_area = np.linalg.norm(cross, axis=1)
    scale = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 1.0
    safe = np.maximum(double_area, 1e-12 * scale * scale)
    rows, cols, vals = [], [], []
    for k in range(3):  # the angle at corner k weighs the opposite edge (k+1, k+2)
        a, b, c = p[k], p[(k + 1) % 3], p[(k + 2) % 3]
        cot = np.einsum("ij,ij->i", b - a, c - a) / safe
        rows += [tri[:, (k + 1) % 3], tri[:, (k + 2) % 3]]
        cols += [tri[:, (k + 2) % 3], tri[:, (k + 1) % 3]]
        vals += [0.5 * cot, 0.5 * cot]
    w = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    lap = (sp.diags(np.asarray(w.sum(axis=1)).ravel()) - w).tocsr()
    mass = np.bincount(tri.ravel(), np.repeat(double_area / 6.0, 3), minlength=n)
    return lap, mass


def stiffness(vertices: np.ndarray, triangles: np.ndarray, n: int, height: float, *,
              membrane: float = MEMBRANE, foundation: float = FOUNDATION) -> sp.csc_matrix:
    """The energy's matrix ``L M^-1 L + membrane/h^2 L + foundation/h^4 M`` (symmetric positive definite)."""
    lap, mass = cotan_laplacian(vertices, triangles, n)
    floor = 1e-9 * (mass.mean() if mass.any() else 1.0)
    mass = np.maximum(mass, floor)  # a vertex in no triangle keeps only its foundation
    k = lap.T @ sp.diags(1.0 / mass) @ lap + (membrane / height ** 2) * lap + sp.diags(foundation / height ** 4 * mass)
    return sp.csc_matrix(k)


class ElasticBody:
    """One elastic part with some vertices held: their displacements in, everyone's out.

    Factorises the free block once (sparse LU); each solve is then one pair of
    triangular solves for the three coordinates together.
    """

    def __init__(self, k: sp.csc_matrix, held: np.ndarray) -> None:
        n = k.shape[0]
        self.n = n
        self.held = np.asarray(held, dtype=np.int64)
        mask = np.ones(n, bool)
        mask[self.held] = False
        self.free = np.flatnonzero(mask)
        self._lu = None
        if len(self.free) and len(self.held):
            rows = k[self.free]
            self._k_fh = rows[:, self.held].tocsr()
            try:
                self._lu = splu(rows[:, self.free].tocsc(), permc_spec=_ORDERING)
            except RuntimeError as exc:  # singular: cannot happen with a positive foundation
                raise FaceError(f"the elastic system cannot be factorised: {exc}",
                                hint="check the mesh for degenerate or duplicated triangles") from None

    def solve(self, held_values: np.ndarray) -> np.ndarray:
        """``(n, 3)`` displacements with ``held_values`` at the held vertices (exactly)."""
        held_values = np.asarray(held_values, dtype=np.float64)
        out = np.zeros((self.n,) + held_values.shape[1:])
        out[self.held] = held_values
        if self._lu is not None:
            out[self.free] = -self._lu.solve(np.asarray(self._k_fh @ held_values))
        return out


def _idw(queries: np.ndarray, sites: np.ndarray, weight: np.ndarray, soft: float) -> np.ndarray:
    """Row-normalised area-weighted inverse-distance weights (power 4), (queries x sites)."""
    out = np.empty((len(queries), len(sites)))
    for a in range(0, len(queries), 256):
        q = queries[a:a + 256]
        r2 = ((q[:, None, :] - sites[None, :, :]) ** 2).sum(-1) + soft * soft
        w = weight / r2 ** (_IDW_POWER / 2)
        out[a:a + 256] = w / w.sum(axis=1, keepdims=True)
    return out


def _affine_design(points: np.ndarray) -> np.ndarray:
    """``[1, x, y, z]`` per point, centred and scaled: the basis of affine fields over a part."""
    centre = points.mean(axis=0)
    span = max(float(np.ptp(points, axis=0).max()), 1e-300)
    return np.column_stack([np.ones(len(points)), (points - centre) / span])


@dataclass(frozen=True)
class _Carried:
    """A part the skin carries: its affine field from the skin's displacement, and its own elastic body."""

    vertices: np.ndarray  # global indices
    design: np.ndarray  # (len(vertices), 4): the part's affine basis
    over_skin: np.ndarray  # (4, n_skin): affine coefficients of the part's field from the skin's displacement
    held: np.ndarray  # which controls sit on this part (indices into the control list)
    body: ElasticBody | None


class ElasticModel:
    """The elastic head for one rest mesh and one set of control vertices.

    ``controls`` are global vertex indices (the sent feature points' vertices);
    :meth:`displacement` maps their residual displacements to every vertex's.
    Controls on the eyeballs are ignored (the eyeballs are rigid, moved by the caller).
    """

    def __init__(self, mesh: HeadMesh, controls: np.ndarray) -> None:
        controls = np.asarray(controls, dtype=np.int64)
        if len(np.unique(controls)) != len(controls):
            raise FaceError("two controls of the elastic model share a vertex",
                            hint="send each feature point once (11.5 is not a control)")
        self.n_vertices = mesh.n_vertices
        self.controls = controls
        height = mesh.height()
        v = mesh.vertices
        a, b = mesh.part_ranges["skin"]
        self._skin = slice(a, b)
        on = (controls >= a) & (controls < b)
        self._skin_held = np.flatnonzero(on)
        k = stiffness(v[a:b], mesh.triangles["skin"] - a, b - a, height)
        self._skin_body = ElasticBody(k, controls[on] - a)
        _, skin_mass = cotan_laplacian(v[a:b], mesh.triangles["skin"] - a, b - a)
        soft = _IDW_SOFT * height
        self._carried: list[_Carried] = []
        meshed = [np.arange(a, b)]
        for part in CARRIED:
            if part not in mesh.part_ranges:
                continue
            pa, pb = mesh.part_ranges[part]
            if pb <= pa:
                continue
            idx = np.arange(pa, pb)
            here = np.flatnonzero((controls >= pa) & (controls < pb))
            body = None
            tris = mesh.triangles.get(part)
            if len(here) and tris is not None and len(tris):
                body = ElasticBody(stiffness(v[pa:pb], tris - pa, pb - pa, height), controls[here] - pa)
            elif len(here):  # points without triangles: each takes its own residual only
                body = ElasticBody(sp.identity(pb - pa, format="csc"), controls[here] - pa)
            # the part takes the best affine fit (least squares) of the skin's field at its vertices, so it
            # keeps its shape instead of following every local wrinkle of the lips next to it (a lip
            # corner moved up would otherwise lift the back teeth through it)
            design = _affine_design(v[idx])
            over_skin = np.linalg.pinv(design, rcond=1e-9) @ _idw(v[idx], v[a:b], skin_mass, soft)
            self._carried.append(_Carried(idx, design, over_skin, here, body))
            meshed.append(idx)
        # the inner points (teeth, tongue) share one affine correction, so that the tongue's sides
        # (6.3/6.4) also tell the teeth how wide the mouth is, as one spatial field would
        self._inner = np.concatenate([c.vertices for c in self._carried]) if self._carried else np.zeros(0, np.int64)
        self._inner_held = np.concatenate([c.held for c in self._carried]) if self._carried else np.zeros(0, np.int64)
        if len(self._inner_held):
            at = v[controls[self._inner_held]]
            self._inner_slopes = np.linalg.pinv(at - at.mean(axis=0), rcond=1e-6)  # (3, k): 0 for one point
            self._inner_offsets = v[self._inner] - at.mean(axis=0)
        meshed_idx = np.concatenate(meshed)
        weights = np.concatenate([skin_mass] + [self._part_mass(mesh, c.vertices) for c in self._carried])
        self._meshed = meshed_idx
        self._joints = np.zeros(0, np.int64)
        self._joint_weights = np.zeros((0, len(meshed_idx)))
        self._joint_held: list[tuple[int, int]] = []
        if "joints" in mesh.part_ranges:
            ja, jb = mesh.part_ranges["joints"]
            self._joints = np.arange(ja, jb)
            self._joint_weights = _idw(v[ja:jb], v[meshed_idx], weights, soft)
            self._joint_held = [(int(c), int(i)) for i, c in enumerate(controls) if ja <= c < jb]

    @staticmethod
    def _part_mass(mesh: HeadMesh, idx: np.ndarray) -> np.ndarray:
        part = next(p for p, (a, b) in mesh.part_ranges.items() if a == idx[0])
        tris = mesh.triangles.get(part)
        if tris is None or not len(tris):
            return np.ones(len(idx))
        _, mass = cotan_laplacian(mesh.vertices[idx[0]:idx[-1] + 1], tris - idx[0], len(idx))
        return np.maximum(mass, 1e-9 * max(mass.mean(), 1e-300))

    def displacement(self, residual: np.ndarray) -> np.ndarray:
        """``(V, 3)`` vertex displacements given ``(n_controls, 3)`` control displacements (eyeballs: 0)."""
        residual = np.asarray(residual, dtype=np.float64)
        if residual.shape != (len(self.controls), 3):
            raise FaceError(f"the elastic model has {len(self.controls)} controls, got displacements "
                            f"shaped {residual.shape}")
        out = np.zeros((self.n_vertices, 3))
        skin = self._skin_body.solve(residual[self._skin_held])
        out[self._skin] = skin
        for c in self._carried:
            out[c.vertices] = c.design @ (c.over_skin @ skin)
        if len(self._inner_held):  # one affine fit of what the inner points still lack, shared by the parts
            miss = residual[self._inner_held] - out[self.controls[self._inner_held]]
            shift = miss.mean(axis=0)
            out[self._inner] += shift + self._inner_offsets @ (self._inner_slopes @ (miss - shift))
        for c in self._carried:
            if c.body is not None:
                at = self.controls[c.held]
                out[c.vertices] += c.body.solve(residual[c.held] - out[at])
        if len(self._joints):
            out[self._joints] = self._joint_weights @ out[self._meshed]
            for vertex, i in self._joint_held:
                out[vertex] = residual[i]
        return out


_CACHE: "OrderedDict[tuple[bytes, bytes], ElasticModel]" = OrderedDict()


def _digest(mesh: HeadMesh) -> bytes:
    h = hashlib.blake2b(digest_size=20)
    h.update(np.ascontiguousarray(mesh.vertices).tobytes())
    for part in sorted(mesh.triangles):
        h.update(part.encode())
        h.update(np.ascontiguousarray(mesh.triangles[part]).tobytes())
    h.update(repr(sorted(mesh.part_ranges.items())).encode())
    h.update(np.ascontiguousarray(mesh.fp_vertex).tobytes())  # the head height the stiffness scales by
    h.update(repr((MEMBRANE, FOUNDATION)).encode())
    return h.digest()


def elastic_model(mesh: HeadMesh, controls: np.ndarray) -> ElasticModel:
    """The (cached) elastic model of ``mesh`` held at vertices ``controls``: built once per mesh and control set."""
    controls = np.asarray(controls, dtype=np.int64)
    key = (_digest(mesh), controls.tobytes())
    model = _CACHE.get(key)
    if model is None:
        model = ElasticModel(mesh, controls)
        _CACHE[key] = model
        while len(_CACHE) > _CACHE_SIZE:
            _CACHE.popitem(last=False)
    else:
        _CACHE.move_to_end(key)
    return model


def elastic_displacement(mesh: HeadMesh, controls: np.ndarray, residual: np.ndarray) -> np.ndarray:
    """``(V, 3)`` displacements of every vertex when vertices ``controls`` move by ``residual`` (eyeballs 0)."""
    return elastic_model(mesh, controls).displacement(residual)


def rest_head(mesh: HeadMesh) -> HeadMesh:
    """The head an elastically calibrated ``mesh`` was shaped from (``mesh`` itself if none, or if moved since)."""
    kept = mesh.info.get(_INFO_KEY)
    if kept is None:
        return mesh
    rest, shaped = kept
    if shaped.shape == mesh.vertices.shape and np.array_equal(shaped, mesh.vertices):
        return rest
    return mesh


def remember_rest(rest: HeadMesh, vertices: np.ndarray) -> dict:
    """The ``HeadMesh.info`` entry by which a head shaped to ``vertices`` from ``rest`` finds ``rest`` again."""
    return {_INFO_KEY: (rest, np.array(vertices, dtype=np.float64, copy=True))}
