"""Exact 3D Sibson (natural-neighbour) coordinates, vectorised over queries.

Used for Dirichlet free-form deformation (DFFD): a mesh vertex ``x`` moves by
``sum_i u_i(x) * dp_i`` where ``u_i(x)`` are the Sibson coordinates of ``x`` with
respect to the control points ``p_i``.  :func:`natural_neighbour_weights` returns
them as a sparse matrix ``W`` (queries x sites): rows sum to 1, ``W @ sites`` gives
the queries back (linear precision), ``W >= 0``, a query on a site gets the unit
row of that site, and row ``q`` is nonzero only on the natural neighbours of
query ``q`` (the sites that would be its Delaunay neighbours were it inserted).

Definition
----------
Insert ``x`` into the Voronoi diagram of the sites; its cell ``V(x)`` steals the
region ``S_i = V(x) ∩ V_old(i)`` from each site ``i``, and
``u_i(x) = vol(S_i) / vol(V(x))``.  ``V(x)`` is bounded only when ``x`` lies
strictly inside the convex hull of the sites, so other queries are refused; add
a cage of zero-displacement control points around the mesh (:func:`cage_points`).

Method (exact up to rounding; no rasterisation, no per-query Python loop)
-------------------------------------------------------------------------
The sites are triangulated once (``scipy.spatial.Delaunay``) and every
tetrahedron ``T`` gets its circumcentre ``c_T`` (an old Voronoi vertex).  The
tetrahedra in *conflict* with ``x`` are those whose circumsphere strictly holds
``x``; the power ``|x - c_T|^2 - R_T^2`` is evaluated densely for a chunk of
queries against all tetrahedra.  ``c_T`` lies in the half-space
``H_i = {y : |y - x| < |y - p_i|}`` of every vertex ``i`` of ``T`` exactly when
``T`` is in conflict, and ``S_i = V_old(i) ∩ H_i``.

``vol(S_i)`` is summed as cones from the apex ``A_i = (x + p_i) / 2``, which lies
on the cutting plane ``∂H_i`` so the new facet (between ``x`` and ``i``)
contributes nothing.  Every other facet of ``S_i`` is an old Voronoi facet
``P_ij`` (dual to the Delaunay edge ``ij``, in the plane bisecting ``p_i p_j``,
through ``m_ij = (p_i + p_j)/2``) clipped to ``H_i``; its cone volume is
``1/6 * sum over its directed boundary edges (a -> b) of
det(m_ij - A_i, a - A_i, b - A_i)``.  That boundary is cut into pieces that each
depend on one conflict tetrahedron only, so that all pieces of all queries are
computed as flat numpy arrays and summed with ``bincount``:

* around the edge ``ij`` the facet runs ``... -> q_ijk -> c_T -> q_ijl -> ...``
  for ``T = (i, j, k, l)`` positively oriented (this orientation is checked
  numerically by the tests against an independent half-space computation);
  ``q_f`` is a point on the Voronoi edge dual to face ``f``: the midpoint of
  ``c_T`` and the neighbour's ``c_T'`` when the neighbour is in conflict too
  (both tetrahedra use the same bitwise point, so the split is exact); otherwise
  (a cavity boundary face) the point ``g_f`` where the edge leaves ``H_i``.  The
  Voronoi edge leaves ``c_T`` along the outward unit normal ``n_f`` of ``f``
  (Delaunay property) and ``|y - x|^2 - |y - p_i|^2`` is affine along it, so
  ``g_f = c_T + t n_f`` with ``t = -pow_T / (2 n_f . (p_i - x))``, clamped to the
  edge's length ``|c_T' - c_T|`` (infinite on the hull).  It uses neither the
  possibly huge ``c_T'`` nor the circumcentre of ``x`` with ``f``;
* the cut segment of ``P_ij`` along ``∂H_i`` joins the ``g_f`` of the two boundary
  faces ending the conflict arc around ``ij``; it is split at ``h_ij``, the
  circumcentre of the triangle ``(x, p_i, p_j)``, which lies on that segment's
  line and depends on ``(x, i, j)`` only.  ``h_ij`` is only needed for boundary
  edges of the cavity, and ``x`` is never collinear with such an edge (a point
  on the line through ``p_i p_j`` outside the segment lies outside every sphere
  through ``p_i`` and ``p_j``), so it stays finite.

This is Watson's idea (signed simplices around each old Voronoi vertex), but it
never uses the circumcentre of ``x`` with an *interior* cavity face, which goes to
infinity when ``x`` is coplanar with that face (``x`` on a Delaunay face or on
its plane), the classic failure of Watson's formula.  Collinear pieces add
exactly (``a x b = a x h + h x b`` for ``h`` on the line ``ab``), which is what
makes the splits exact.

Degeneracies
------------
The triangulation is ``Delaunay(sites, qhull_options="Qbb Qc Qz Q12")`` (scipy's
defaults; scipy adds ``Qt``, triangulated output).  No joggle: ``QJ`` would
triangulate slightly moved sites, and its slivers are flat in the true
coordinates anyway.

* Co-spherical sites (a regular grid): several tetrahedra share one
  circumcentre; their pieces are zero-length, which is harmless.  A query *on*
  a circumsphere is a tie of the strict conflict test; either answer gives the
  same volumes since that tetrahedron's pieces shrink to nothing there.
* Flat tetrahedra: ``Qt`` splits co-spherical cells and may emit zero-volume
  tetrahedra of four co-circular coplanar sites (38 of the 200 tetrahedra of a
  4x4x4 grid).  Circumcentres are computed as the least-squares intersection of
  the six edges' bisector planes (unit normals, relative to the centroid, via
  an SVD): well conditioned for any tetrahedron whose edge directions span
  space, including one with a very short edge.  A tetrahedron whose edge
  directions are coplanar (smallest singular value below ``1e-10``) is flat; if
  its sites are co-circular the truncated solution is a point of the circle's
  axis, which also holds its neighbours' circumcentres, and any point of that
  axis gives the same volumes (the pieces through it are collinear).  Its
  orientation cannot be read from its determinant, so it is taken from the
  triangulation (a tetrahedron and its neighbour induce opposite orientations
  on their shared face), propagated from non-flat neighbours.
* Hull slivers: four nearly coplanar (not co-circular) or nearly collinear
  sites on the hull give a huge circumsphere whose centre is also the least
  accurate.  A tetrahedron that is flat but not co-circular, nearly collinear
  (two small singular values), or whose circumradius or smallest face
  circumradius exceeds ``1e8`` x the sites' bounding-box diagonal is never in
  conflict: inside the hull its sphere is a half-space beyond the hull, except
  within about ``1e-9`` of the diagonal of the hull.  Queries within about
  ``1e-8`` x diagonal of a nearly planar, jittered stretch of hull can lose
  accuracy (round-off makes such spheres ill-determined); a cage
  (:func:`cage_points`) keeps every mesh vertex far from the hull.
* Every computed row is checked (finite, weights ``>= -1e-8``, linear
  precision within ``1e-8`` x diagonal); rows that fail raise
  :class:`FaceError` rather than return wrong weights.
* The power of a query for each sphere is ``|x|^2 - 2 x . c + K`` with
  ``K = |p0|^2 + 2 p0 . (c - p0)``, in coordinates centred on the sites'
  bounding box, so large circumcentres lose little.
* Coincident sites (within ``atol``), sites qhull leaves out of the
  triangulation (nearly coincident ones), fewer than 4 sites, and sites that
  span no volume raise :class:`FaceError`.
* A query within ``atol`` of a site gets that site's unit row (the formula
  degenerates there since ``∂H_i`` is undefined).  Other queries must lie inside
  the hull (``scipy.spatial.ConvexHull`` facets) by more than ``atol``; queries
  outside or on the hull raise :class:`FaceError`.
* Weights below ``1e-14`` (rounding residue of near-ties) are dropped and the
  row renormalised.

Speed: about 0.14 s for 5,000 queries against 114 sites (100 + a cage, about
620 tetrahedra) on one core, 0.45 s for 20,000 (``tools/bench_sibson.py``);
queries are processed in chunks of about 10^6 query x tetrahedron pairs so
that memory stays bounded.
"""
from __future__ import annotations

from itertools import permutations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import ConvexHull, Delaunay, QhullError, cKDTree

from .errors import FaceError
from .points import as_points, reject_duplicates

__all__ = ["NaturalNeighbours", "cage_points", "inside_hull", "natural_neighbour_weights"]

_WHERE = "natural_neighbour_weights"
_CAGE_HINT = "add bounding control points (see cage_points)"
_FLAT_TOL = 1e-10  # flat tetrahedron: its edge directions span a volume below this
_HUGE = 1e8  # circumradius above this x bbox diagonal: never in conflict
_NEEDLE_TOL = 1e-6  # nearly collinear: two edge-direction singular values below this
_COCIRCULAR_TOL = 1e-6  # flat and co-circular: residual <= this * (longest edge)^2
_DROP_TOL = 1e-14  # weights below this are rounding residue
_CHECK_TOL = 1e-8  # self-check of every row: linear precision (x diagonal), weights >= -this
_CHUNK_ELEMENTS = 1_000_000  # queries x tetrahedra per chunk


def _parity(perm) -> int:
    """+1 for an even permutation of range(len(perm)), -1 for an odd one."""
    perm = list(perm)
    sign = 1
    for a in range(len(perm)):
        while perm[a] != a:
            b = perm[a]
            perm[a], perm[b] = perm[b], perm[a]
            sign = -sign
    return sign


# The 6 vertex-slot pairs a < b of a tetrahedron, each completed to an even
# permutation (a, b, c, d): for a positively oriented T, (T[a], T[b], T[c], T[d])
# = (i, j, k, l) is positive too, and so is (j, i, l, k).
_PAIRS = np.array(
    [
        next(p for p in permutations(range(4)) if p[:2] == (a, b) and _parity(p) == 1)
        for a in range(4)
        for b in range(a + 1, 4)
    ],
    dtype=np.intp,
)
# Slots of the face opposite slot m, ordered so that (f0, f1, f2, m) is even
# (then (p_f1 - p_f0) x (p_f2 - p_f0) points to the side of vertex m).
_FACE = np.array(
    [next(p for p in permutations(sorted(set(range(4)) - {m})) if _parity((*p, m)) == 1) for m in range(4)],
    dtype=np.intp,
)
# For the face opposite slot m: its 3 slot pairs (a, b) and the sign of the
# permutation (a, b, c, m), c the third slot of the face (the pair (b, a) has
# the opposite sign).
_FPAIR_A = np.empty((4, 3), dtype=np.intp)
_FPAIR_B = np.empty((4, 3), dtype=np.intp)
_FPAIR_S = np.empty((4, 3))
for _m in range(4):
    for _n, (_a, _b, _c) in enumerate([(0, 1, 2), (0, 2, 1), (1, 2, 0)]):
        _a, _b, _c = _FACE[_m, _a], _FACE[_m, _b], _FACE[_m, _c]
        _FPAIR_A[_m, _n], _FPAIR_B[_m, _n] = _a, _b
        _FPAIR_S[_m, _n] = _parity((_a, _b, _c, _m))
del _m, _n, _a, _b, _c


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cross product along the last axis (faster than np.cross on small stacks)."""
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    out[..., 0] = u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1]
    out[..., 1] = u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2]
    out[..., 2] = u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
    return out


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Dot product along the last axis (faster than a sum over an axis of 3)."""
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]


def _triple(e: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """det(e, u, v) = e . (u x v) along the last axis."""
    return (
        e[..., 0] * (u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1])
        + e[..., 1] * (u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2])
        + e[..., 2] * (u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0])
    )


class NaturalNeighbours:
    """Sibson coordinates with respect to fixed ``sites`` (triangulated once).

    ``atol`` (default ``1e-9`` x the sites' bounding-box diagonal) is the distance
    below which a query counts as coinciding with a site, and the least depth
    inside the hull a query needs; sites closer than ``atol`` are rejected.
    """

    def __init__(self, sites, *, atol: float | None = None) -> None:
        sites = as_points(sites, "sites", _WHERE)
        n = len(sites)
        if n < 4:
            raise FaceError(f"need at least 4 sites spanning a volume, got {n}", where=_WHERE, hint=_CAGE_HINT)
        lo, hi = sites.min(axis=0), sites.max(axis=0)
        diag = float(np.linalg.norm(hi - lo))
        if atol is None:
            atol = 1e-9 * diag
        atol = float(atol)
        if not (np.isfinite(atol) and atol >= 0):
            raise FaceError(f"atol must be a finite number >= 0, got {atol}", where=_WHERE)
        self.atol = atol
        self._diag = diag
        self.centre = (lo + hi) / 2
        self.sites = sites.copy()
        self.sites.flags.writeable = False
        P = sites - self.centre
        self._P = P
        self._tree = cKDTree(P)
        reject_duplicates(P, atol, "sites", _WHERE, "merge or drop duplicate control points")
        try:
            tri = Delaunay(P, qhull_options="Qbb Qc Qz Q12")
        except (QhullError, ValueError) as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise FaceError(
                f"the {n} sites cannot be triangulated (coplanar or degenerate?): {first}",
                where=_WHERE,
                hint=_CAGE_HINT,
            ) from None
        if len(tri.coplanar):
            k, j = int(tri.coplanar[0, 0]), int(tri.coplanar[0, 2])
            raise FaceError(
                f"{len(tri.coplanar)} site(s) too close to others to be triangulated, first site {k} (near site {j})",
                where=_WHERE,
                hint="merge nearly coincident control points",
            )
        self._setup(tri)

    # -- one-time geometry -------------------------------------------------
    def _setup(self, tri: Delaunay) -> None:
        P = self._P
        S = np.array(tri.simplices, dtype=np.intp)
        N = np.array(tri.neighbors, dtype=np.intp)
        nt = len(S)
        # Circumcentres as the least-squares intersection of the six edges'
        # bisector planes, unit normals, relative to the centroid: well
        # conditioned unless all six edges are nearly coplanar (a flat
        # tetrahedron), also for a tetrahedron with one very short edge.
        V = P[S]
        o = V.mean(axis=1)
        Vr = V - o[:, None, :]
        a, b = np.array([0, 0, 0, 1, 1, 2]), np.array([1, 2, 3, 2, 3, 3])
        Ed = Vr[:, b] - Vr[:, a]
        length = np.sqrt((Ed**2).sum(axis=2))
        U = Ed / length[..., None]
        rhs = (U * (0.5 * (Vr[:, a] + Vr[:, b]))).sum(axis=2)
        Lu, sig, Vt = np.linalg.svd(U, full_matrices=False)
        flat = sig[:, 2] <= _FLAT_TOL * sig[:, 0]
        inv = np.divide(1.0, sig, out=np.zeros_like(sig), where=sig > _FLAT_TOL * sig[:, :1])
        cr = np.einsum("tji,tj->ti", Vt, inv * np.einsum("tkj,tk->tj", Lu, rhs))
        C = o + cr
        lmax = length.max(axis=1)
        E = V[:, 1:] - V[:, :1]
        det = np.linalg.det(E)
        # Orient the non-flat tetrahedra positively (swap slots 0 and 1).
        swap = (det < 0) & ~flat
        S[swap, 0], S[swap, 1] = S[swap, 1], S[swap, 0].copy()
        N[swap, 0], N[swap, 1] = N[swap, 1], N[swap, 0].copy()
        # Flat ones: orientation from an oriented neighbour (combinatorial).
        todo = set(np.flatnonzero(flat).tolist())
        while todo:
            progress = False
            for t in sorted(todo):
                for m in range(4):
                    u = N[t, m]
                    if u < 0 or u in todo:
                        continue
                    mu = int(np.flatnonzero(N[u] == t)[0])
                    tup = S[t].copy()
                    tup[m] = S[u, mu]
                    perm = [int(np.flatnonzero(S[u] == v)[0]) for v in tup]
                    # A positive t turns negative when its vertex m is swapped for
                    # the neighbour's opposite vertex.
                    if _parity(perm) == 1:
                        S[t, 0], S[t, 1] = S[t, 1], S[t, 0]
                        N[t, 0], N[t, 1] = N[t, 1], N[t, 0]
                    todo.discard(t)
                    progress = True
                    break
            if not progress:  # flat tetrahedra touching no oriented one: leave them
                break
        finite = np.ones(nt, dtype=bool)
        if flat.any():
            # The least-squares centre of co-circular flat sites lies on their
            # circle's axis.  Flat but not co-circular (a sliver on a nearly
            # planar stretch of the hull): the circumsphere is a half-space
            # beyond the hull, never in conflict with a query inside.
            fi = np.flatnonzero(flat)
            r2 = ((P[S[fi]] - C[fi, None, :]) ** 2).sum(axis=2)
            cocircular = np.ptp(r2, axis=1) <= _COCIRCULAR_TOL * lmax[fi] ** 2
            finite[fi[~cocircular]] = False
        # A circumsphere far larger than the sites (a hull sliver: nearly
        # coplanar or collinear sites on the hull) is, inside the hull, a
        # half-space beyond it; its centre is also the least accurate.
        # Nearly collinear sites (every face a needle) make the least-squares
        # centre meaningless, so also test the smallest face circumradius, a
        # lower bound of the circumradius (r = abc / 4 area).
        ia, ib, ic = [3, 1, 0, 0], [4, 2, 2, 1], [5, 5, 4, 3]  # edges of the face opposite vertex 0..3
        area2 = np.linalg.norm(_cross(Ed[:, ia], Ed[:, ib]), axis=2)
        abc = length[:, ia] * length[:, ib] * length[:, ic]
        rface = np.divide(abc, 2.0 * area2, out=np.full_like(area2, np.inf), where=area2 > 0)
        huge = _HUGE * self._diag
        needle = sig[:, 1] <= _NEEDLE_TOL * sig[:, 0]
        finite &= (np.sqrt((cr**2).sum(axis=1)) <= huge) & (rface.min(axis=1) <= huge) & ~needle
        C[~finite] = 0.0
        self._S, self._N = S, N
        self._P0 = P[S[:, 0]]
        D = C - self._P0
        # power(x) = |x - p0|^2 - 2 (x - p0).D = |x|^2 - 2 x.C + K
        K = (self._P0 * self._P0).sum(axis=1) + 2.0 * (self._P0 * D).sum(axis=1)
        K[~finite] = np.inf
        self._C, self._K = C, K
        # Outward unit normal of every face (slot m: the face opposite vertex m),
        # a vertex of it, and the length of its Voronoi edge (inf if unbounded).
        F = S[:, _FACE]  # (nt, 4, 3), (f0, f1, f2, m) even
        nrm = -_cross(P[F[..., 1]] - P[F[..., 0]], P[F[..., 2]] - P[F[..., 0]])
        length = np.linalg.norm(nrm, axis=2)
        self._FN = nrm / np.where(length > 0, length, 1.0)[..., None]
        self._FA = P[F[..., 0]]
        nb = np.where(N < 0, 0, N)
        seg = np.linalg.norm(C[nb] - C[:, None, :], axis=2)
        self._SEG = np.where((N >= 0) & finite[nb] & finite[:, None], seg, np.inf)
        # Convex hull facets (qhull merges coplanar ones) for the inside test.
        try:
            hull = ConvexHull(P)
        except (QhullError, ValueError) as exc:  # pragma: no cover - Delaunay succeeded
            raise FaceError(f"convex hull of the sites failed: {exc}", where=_WHERE, hint=_CAGE_HINT) from None
        self._hull_normal = hull.equations[:, :3]
        self._hull_offset = -hull.equations[:, 3]

    # -- queries -------------------------------------------------------------
    def _classify(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(nearest site, snapped to it?, strictly inside the hull?) for centred queries."""
        dist, nearest = self._tree.query(X)
        snap = dist <= self.atol
        inside = np.zeros(len(X), dtype=bool)
        step = max(1, _CHUNK_ELEMENTS // max(1, len(self._hull_offset)))
        for s in range(0, len(X), step):
            sd = X[s : s + step] @ self._hull_normal.T - self._hull_offset
            inside[s : s + step] = sd.max(axis=1) < -self.atol
        return nearest, snap, inside

    def inside(self, queries) -> np.ndarray:
        """True where the weights are defined: inside the hull by more than ``atol``, or on a site."""
        X = as_points(queries, "queries", _WHERE) - self.centre
        _, snap, inside = self._classify(X)
        return snap | inside

    def weights(self, queries) -> sp.csr_matrix:
        """Sibson coordinates of ``queries`` as a CSR matrix (queries x sites)."""
        X = as_points(queries, "queries", _WHERE) - self.centre
        m, n = len(X), len(self._P)
        nearest, snap, inside = self._classify(X)
        bad = ~(snap | inside)
        if bad.any():
            first = int(np.flatnonzero(bad)[0])
            raise FaceError(
                f"{int(bad.sum())} of {m} queries lie outside the convex hull of the {n} sites "
                f"(or on it, within {self.atol:g}); first is query {first}",
                where=_WHERE,
                hint=_CAGE_HINT,
            )
        rows = [np.flatnonzero(snap)]
        cols = [nearest[snap]]
        vals = [np.ones(int(snap.sum()))]
        active = np.flatnonzero(~snap)
        step = max(1, _CHUNK_ELEMENTS // len(self._S))
        failed = []
        for s in range(0, len(active), step):
            idx = active[s : s + step]
            block = self._block(X[idx])
            # Self-check: rows must be finite, non-negative and reproduce x.
            err = np.abs(block @ self._P - X[idx]).max(axis=1)
            bad = ~(err <= _CHECK_TOL * self._diag) | ~(block.min(axis=1) >= -_CHECK_TOL)
            failed.append(idx[bad])
            r, c = np.nonzero(block)
            rows.append(idx[r])
            cols.append(c)
            vals.append(block[r, c])
        failed = np.concatenate(failed) if failed else np.empty(0, dtype=np.intp)
        if len(failed):
            raise FaceError(
                f"{len(failed)} of {m} queries lie too close to the hull (where its sites are nearly "
                f"coplanar) for accurate weights; first is query {int(failed[0])}",
                where=_WHERE,
                hint=_CAGE_HINT,
            )
        W = sp.coo_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, n)
        ).tocsr()
        W.sort_indices()
        return W

    def _block(self, X: np.ndarray) -> np.ndarray:
        """Dense weights (len(X) x n) for centred queries strictly inside the hull."""
        P, S, N, C = self._P, self._S, self._N, self._C
        nq, n = len(X), len(P)
        # Power of every query with respect to every circumsphere.
        power = X @ (-2.0 * C.T)
        power += self._K
        power += _dot(X, X)[:, None]
        conflict = power < 0.0
        qi, ti = np.nonzero(conflict)
        x = X[qi]  # (np, 3)
        c = C[ti]
        pT = power[qi, ti]
        nb = N[ti]  # (np, 4)
        nbc = np.where(nb < 0, 0, nb)
        inner = conflict[qi[:, None], nbc] & (nb >= 0)
        cN = C[nbc]
        # A point of the Voronoi edge dual to each face (see module docstring):
        # the midpoint of two conflict circumcentres, or where the edge leaves
        # the region closer to x (the power is affine along it).
        Q = 0.5 * (c[:, None, :] + cN)
        bd = ~inner
        pb, mb = np.nonzero(bd)
        if len(pb):
            tb = ti[pb]
            nrm = self._FN[tb, mb]
            den = 2.0 * _dot(nrm, self._FA[tb, mb] - x[pb])
            t = np.divide(-pT[pb], den, out=np.zeros_like(den), where=den != 0.0)
            seg = self._SEG[tb, mb]
            np.clip(t, -seg, seg, out=t)
            Q[pb, mb] = c[pb] + t[:, None] * nrm
        St = S[ti]  # (np, 4) site indices of each conflict tetrahedron
        U = P[St] - x[:, None, :]  # vertices relative to x
        # Voronoi-edge pieces: for (i, j, k, l) = T[a, b, c, d] positive, the facet
        # P_ij runs q_ijk -> c_T -> q_ijl (q_ijk on the face opposite slot d); its
        # cone from A_i = x + u_i/2 with m_ij - A_i = u_j/2 is
        # u_j/2 . ((q_ijk - q_ijl) x (c_T - x - u_i/2)).  The pair (j, i) runs
        # the other way (q_jil = q_ijl), which shares the products below.
        Ua = U[:, _PAIRS[:, 0]]
        Ub = U[:, _PAIRS[:, 1]]
        dq = Q[:, _PAIRS[:, 3]] - Q[:, _PAIRS[:, 2]]
        w = _cross(dq, (c - x)[:, None, :])
        t2 = 0.25 * _triple(Ub, dq, Ua)
        vol_ab = 0.5 * _dot(Ub, w) - t2
        vol_ba = -0.5 * _dot(Ua, w) - t2
        key_rows = [np.repeat(qi, 12)]
        key_cols = [np.concatenate([St[:, _PAIRS[:, 0]], St[:, _PAIRS[:, 1]]], axis=1).ravel()]
        key_vals = [np.concatenate([vol_ab, vol_ba], axis=1).ravel()]
        # Cut pieces along the plane between x and i, split at h_ij (the
        # circumcentre of x, p_i, p_j; the same point for the pair (j, i)).
        if len(pb):
            rows3 = np.arange(len(pb))[:, None]
            Ub_ = U[pb]
            u = Ub_[rows3, _FPAIR_A[mb]]  # p_i - x
            v = Ub_[rows3, _FPAIR_B[mb]]  # p_j - x
            sign = _FPAIR_S[mb]
            wn = _cross(u, v)
            r = (_dot(u, u)[..., None] * _cross(v, wn) + _dot(v, v)[..., None] * _cross(wn, u)) / (
                2.0 * _dot(wn, wn)[..., None]
            )  # h - x
            gx = (Q[pb, mb] - x[pb])[:, None, :]
            # pair (i, j): s/2 v . ((r - u/2) x (g - x - u/2)); pair (j, i): -s/2 u . ((r - v/2) x (g - x - v/2))
            rg = _cross(r, gx)
            shared = 0.5 * (_triple(v, r, u) + _triple(v, u, gx))  # enters both with opposite signs
            vol_ij = 0.5 * sign * (_dot(v, rg) - shared)
            vol_ji = -0.5 * sign * (_dot(u, rg) + shared)
            Sb = St[pb]
            key_rows.append(np.repeat(qi[pb], 6))
            key_cols.append(np.concatenate([Sb[rows3, _FPAIR_A[mb]], Sb[rows3, _FPAIR_B[mb]]], axis=1).ravel())
            key_vals.append(np.concatenate([vol_ij, vol_ji], axis=1).ravel())
        keys = np.concatenate(key_rows) * n + np.concatenate(key_cols)
        block = np.bincount(keys, weights=np.concatenate(key_vals), minlength=nq * n).reshape(nq, n)
        total = block.sum(axis=1, keepdims=True)
        block /= total
        block[np.abs(block) < _DROP_TOL] = 0.0
        block /= block.sum(axis=1, keepdims=True)
        return block


def natural_neighbour_weights(sites: np.ndarray, queries: np.ndarray, *, atol: float | None = None) -> sp.csr_matrix:
    """Sibson coordinates of ``queries`` (m x 3) with respect to ``sites`` (n x 3).

    Returns a CSR matrix ``W`` (m x n) with rows summing to 1, ``W >= 0`` and
    ``W @ sites == queries`` up to rounding; a query within ``atol`` (default
    ``1e-9`` x the sites' bounding-box diagonal) of a site gets that site's unit
    row.  Every query must lie inside the sites' convex hull by more than
    ``atol`` (else :class:`FaceError`); surround the mesh with
    :func:`cage_points`.  To evaluate several query sets against the same sites,
    build a :class:`NaturalNeighbours` once.
    """
    return NaturalNeighbours(sites, atol=atol).weights(queries)


def inside_hull(sites: np.ndarray, queries: np.ndarray, *, atol: float | None = None) -> np.ndarray:
    """Boolean mask of the queries whose Sibson coordinates are defined.

    True for queries strictly inside the convex hull of ``sites`` (by more than
    ``atol``) and for queries within ``atol`` of a site; False for the rest
    (outside, or on the hull where the Voronoi cell would be unbounded).
    """
    return NaturalNeighbours(sites, atol=atol).inside(queries)


def cage_points(points: np.ndarray, margin: float = 0.25) -> np.ndarray:
    """14 extra control points enclosing ``points``: corners and face centres of a box.

    The box is the points' axis-aligned bounding box grown on every side by
    ``margin`` x its largest extent, so it holds ``points`` and anything within
    that distance of their bounding box strictly inside.  Sibson coordinates are
    undefined outside the convex hull of the control points (the inserted
    point's Voronoi cell is unbounded there), so a mesh whose vertices stray
    beyond the feature points cannot be deformed by them alone.  Adding these
    points as controls with zero displacement keeps the coordinates defined
    everywhere in the box and makes the deformation fade out towards it:
    vertices far from every moved feature point stay where the global alignment
    put them.  The face centres keep the tetrahedra next to the box faces from
    spanning the whole box, which would give every corner a say everywhere.
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise FaceError(f"points must have shape (n, 3) with n >= 1, not {pts.shape}", where="cage_points")
    if not np.isfinite(pts).all():
        raise FaceError("points must be finite", where="cage_points")
    margin = float(margin)
    if not (np.isfinite(margin) and margin > 0):
        raise FaceError(f"margin must be > 0, got {margin}", where="cage_points")
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    extent = float((hi - lo).max())
    if extent <= 0:
        raise FaceError("points all coincide; the cage size is undefined", where="cage_points")
    pad = margin * extent
    lo, hi = lo - pad, hi + pad
    mid = (lo + hi) / 2
    ends = (lo, hi)
    corners = np.array([[ends[a][0], ends[b][1], ends[c][2]] for a in (0, 1) for b in (0, 1) for c in (0, 1)])
    faces = []
    for axis in range(3):
        for end in (lo, hi):
            f = mid.copy()
            f[axis] = end[axis]
            faces.append(f)
    return np.vstack([corners, np.array(faces)])
