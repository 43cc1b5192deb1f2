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
  (a cavity boundary face) the point ``g_f`` where the edge leaves ``H_i``,
  found by linear interpolation of the power along ``c_T -> c_T'``
  (``t = pow_T / (pow_T - pow_T')``, always in ``[0, 1]``, so ``g_f`` stays between
  two Voronoi vertices and never blows up), or along the outward Voronoi ray of a
  convex-hull face;
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
* Co-spherical sites (a regular grid): several tetrahedra share one
  circumcentre; their pieces are zero-length edges, which is harmless.  A query
  *on* a circumsphere is a tie of the strict conflict test; either answer gives
  the same volumes, because such a tetrahedron's pieces shrink to zero there, and
  ``g_f`` interpolation keeps them bounded if rounding classifies two tetrahedra
  sharing a centre differently.
* Flat tetrahedra: qhull's triangulated output (option ``Qt``, which scipy
  always adds) splits co-spherical cells and may emit zero-volume tetrahedra of
  four co-circular coplanar sites (38 of 200 for a 4x4x4 grid).  A tetrahedron
  with ``|det| <= 1e-10 * (longest edge)^3`` is treated as flat: its circumcentre
  is the least-squares (pseudo-inverse) one, the circle centre, which lies on
  the common axis that also holds its neighbours' circumcentres; any point of
  that axis gives the same volumes since the pieces through it are collinear.
  Its orientation cannot be read from its determinant, so it is taken from the
  triangulation (a tetrahedron and its neighbour induce opposite orientations on
  their shared face), propagated from non-flat neighbours.
* Near-flat slivers keep their (possibly large) circumcentres; coordinates are
  centred on the sites' bounding box and the power is evaluated as
  ``|x - p0|^2 - 2 (x - p0) . (c - p0)`` so that large circumcentres lose little.
* Sites that qhull leaves out of the triangulation (``coplanar`` points, e.g.
  nearly coincident sites) make the triangulation be rebuilt with joggle
  (``QJ``); coincident sites (within ``atol``) and fewer than 4 sites, or
  sites that span no volume, raise :class:`FaceError`.
* A query within ``atol`` of a site gets that site's unit row (the formula
  degenerates there since ``∂H_i`` is undefined).  Other queries must lie inside
  the hull by more than ``atol``; queries outside or on the hull raise
  :class:`FaceError`.
* Tiny weights (``|u| < 1e-14``, rounding residue of near-ties) are dropped and
  the row renormalised.

Speed: about 0.1-0.2 s for 5,000 queries against 100 sites on one core
(see ``tools/bench_sibson.py``); queries are processed in chunks so that memory
stays bounded.
"""
from __future__ import annotations

from itertools import permutations

import numpy as np
import scipy.sparse as sp
from scipy.spatial import Delaunay, QhullError, cKDTree

from .errors import FaceError

__all__ = ["NaturalNeighbours", "cage_points", "inside_hull", "natural_neighbour_weights"]

_WHERE = "natural_neighbour_weights"
_CAGE_HINT = "add bounding control points (see cage_points)"
_FLAT_TOL = 1e-10  # |det| <= _FLAT_TOL * (longest edge)^3: flat tetrahedron
_DROP_TOL = 1e-14  # weights below this are rounding residue
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


# The 12 even permutations (a, b, c, d) of a tetrahedron's vertex slots: for a
# positively oriented T, (T[a], T[b], T[c], T[d]) = (i, j, k, l) is positive too.
_EVEN = np.array([p for p in permutations(range(4)) if _parity(p) == 1], dtype=np.intp)
# Slots of the face opposite slot m, ordered so that (f0, f1, f2, m) is even
# (then (p_f1 - p_f0) x (p_f2 - p_f0) points to the side of vertex m).
_FACE = np.array(
    [next(p for p in permutations(sorted(set(range(4)) - {m})) if _parity((*p, m)) == 1) for m in range(4)],
    dtype=np.intp,
)
# For the face opposite slot m: its 6 ordered slot pairs (a, b) and the sign of
# the permutation (a, b, c, m), c the third slot of the face.
_BPAIR_A = np.empty((4, 6), dtype=np.intp)
_BPAIR_B = np.empty((4, 6), dtype=np.intp)
_BPAIR_S = np.empty((4, 6))
for _m in range(4):
    for _n, (_a, _b) in enumerate(permutations(_FACE[_m], 2)):
        _c = (set(_FACE[_m]) - {_a, _b}).pop()
        _BPAIR_A[_m, _n], _BPAIR_B[_m, _n] = _a, _b
        _BPAIR_S[_m, _n] = _parity((_a, _b, _c, _m))
del _m, _n, _a, _b, _c


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cross product along the last axis (faster than np.cross on small stacks)."""
    out = np.empty(np.broadcast_shapes(u.shape, v.shape))
    out[..., 0] = u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1]
    out[..., 1] = u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2]
    out[..., 2] = u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]
    return out


def _triple(e: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """det(e, u, v) = e . (u x v) along the last axis."""
    return (
        e[..., 0] * (u[..., 1] * v[..., 2] - u[..., 2] * v[..., 1])
        + e[..., 1] * (u[..., 2] * v[..., 0] - u[..., 0] * v[..., 2])
        + e[..., 2] * (u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0])
    )


def _as_points(array, name: str) -> np.ndarray:
    try:
        pts = np.asarray(array, dtype=float)
    except (TypeError, ValueError) as exc:
        raise FaceError(f"{name} must be an array of 3D points: {exc}", where=_WHERE) from None
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise FaceError(f"{name} must have shape (n, 3), not {pts.shape}", where=_WHERE)
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any():
        raise FaceError(
            f"{name} has {int(bad.sum())} non-finite point(s), first at index {int(np.flatnonzero(bad)[0])}",
            where=_WHERE,
        )
    return pts


class NaturalNeighbours:
    """Sibson coordinates with respect to fixed ``sites`` (triangulated once).

    ``atol`` (default ``1e-9`` x the sites' bounding-box diagonal) is the distance
    below which a query counts as coinciding with a site, and the least depth
    inside the hull a query needs; sites closer than ``atol`` are rejected.
    """

    def __init__(self, sites, *, atol: float | None = None) -> None:
        sites = _as_points(sites, "sites")
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
        self.centre = (lo + hi) / 2
        self.sites = sites
        P = sites - self.centre
        self._P = P
        self._tree = cKDTree(P)
        pairs = sorted(self._tree.query_pairs(atol))
        if pairs:
            shown = ", ".join(f"{a} and {b}" for a, b in pairs[:5])
            more = f" (and {len(pairs) - 5} more pairs)" if len(pairs) > 5 else ""
            raise FaceError(
                f"{len(pairs)} pair(s) of sites coincide within {atol:g}: {shown}{more}",
                where=_WHERE,
                hint="merge or drop duplicate control points",
            )
        tri = None
        for options in ("Qbb Qc Qz Q12", "QJ Qbb Q12"):
            try:
                tri = Delaunay(P, qhull_options=options)
            except (QhullError, ValueError) as exc:
                first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
                raise FaceError(
                    f"the {n} sites cannot be triangulated (coplanar or degenerate?): {first}",
                    where=_WHERE,
                    hint=_CAGE_HINT,
                ) from None
            if len(tri.coplanar) == 0:
                break
        else:
            k = int(tri.coplanar[0, 0])
            raise FaceError(
                f"{len(tri.coplanar)} site(s) were left out of the Delaunay triangulation, first site {k}",
                where=_WHERE,
                hint="sites nearly coincide; merge them",
            )
        self._setup(tri)

    # -- one-time geometry -------------------------------------------------
    def _setup(self, tri: Delaunay) -> None:
        P = self._P
        S = np.array(tri.simplices, dtype=np.intp)
        N = np.array(tri.neighbors, dtype=np.intp)
        nt = len(S)
        E = P[S[:, 1:]] - P[S[:, :1]]
        det = np.linalg.det(E)
        edges = np.concatenate([E, (E[:, [1, 2, 0]] - E)], axis=1)
        lmax = np.sqrt((edges**2).sum(axis=2).max(axis=1))
        flat = np.abs(det) <= _FLAT_TOL * lmax**3
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
            if not progress:  # a component of flat tetrahedra only: cannot happen for a 3D hull
                raise FaceError("the sites' triangulation is degenerate", where=_WHERE, hint=_CAGE_HINT)
        E = P[S[:, 1:]] - P[S[:, :1]]
        rhs = 0.5 * (E**2).sum(axis=2)
        D = np.empty((nt, 3))
        ok = ~flat
        if ok.any():
            D[ok] = np.linalg.solve(E[ok], rhs[ok][..., None])[..., 0]
        if flat.any():
            D[flat] = (np.linalg.pinv(E[flat], rcond=1e-8) @ rhs[flat][..., None])[..., 0]
        self._S, self._N = S, N
        self._P0 = P[S[:, 0]]
        self._D = D  # circumcentre minus first vertex
        self._C = self._P0 + D  # circumcentres (centred coordinates)
        # power(x) = |x - p0|^2 - 2 (x - p0).D = |x|^2 - 2 x.C + K
        self._K = (self._P0 * self._P0).sum(axis=1) + 2.0 * (self._P0 * D).sum(axis=1)
        # Outward unit normals of convex-hull faces (zero elsewhere).
        F = S[:, _FACE]  # (nt, 4, 3) face vertices, (f0, f1, f2, m) even
        nrm = -_cross(P[F[..., 1]] - P[F[..., 0]], P[F[..., 2]] - P[F[..., 0]])
        hull = N < 0
        length = np.linalg.norm(nrm, axis=2)
        nrm = np.where(hull[..., None], nrm / np.where(length > 0, length, 1.0)[..., None], 0.0)
        self._HN = nrm
        self._FA = P[F[..., 0]]  # a vertex of each face
        ht, hm = np.nonzero(hull)
        self._hull_normal = nrm[ht, hm]
        self._hull_offset = (self._hull_normal * self._FA[ht, hm]).sum(axis=1)

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
        X = _as_points(queries, "queries") - self.centre
        _, snap, inside = self._classify(X)
        return snap | inside

    def weights(self, queries) -> sp.csr_matrix:
        """Sibson coordinates of ``queries`` as a CSR matrix (queries x sites)."""
        X = _as_points(queries, "queries") - self.centre
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
        for s in range(0, len(active), step):
            idx = active[s : s + step]
            block = self._block(X[idx])
            r, c = np.nonzero(block)
            rows.append(idx[r])
            cols.append(c)
            vals.append(block[r, c])
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
        power += (X * X).sum(axis=1)[:, None]
        conflict = power < 0.0
        qi, ti = np.nonzero(conflict)
        x = X[qi]  # (np, 3)
        c = C[ti]
        pT = power[qi, ti]
        nb = N[ti]  # (np, 4)
        hull = nb < 0
        nbc = np.where(hull, 0, nb)
        inner = conflict[qi[:, None], nbc] & ~hull
        pN = power[qi[:, None], nbc]
        cN = C[nbc]
        # A point of the Voronoi edge dual to each face (see module docstring).
        Q = 0.5 * (c[:, None, :] + cN)
        cut = ~inner & ~hull
        if cut.any():
            pq, mq = np.nonzero(cut)
            p0, p1 = pT[pq], pN[pq, mq]
            t = p0 / (p0 - p1)
            Q[pq, mq] = c[pq] + t[:, None] * (cN[pq, mq] - c[pq])
        if hull.any():
            pq, mq = np.nonzero(hull)
            nrm = self._HN[ti[pq], mq]
            depth = 2.0 * (nrm * (self._FA[ti[pq], mq] - x[pq])).sum(axis=1)
            t = -pT[pq] / depth
            Q[pq, mq] = c[pq] + t[:, None] * nrm
        St = S[ti]  # (np, 4) site indices of each conflict tetrahedron
        # Voronoi-edge pieces: for (i, j, k, l) = T[a, b, c, d] positive, the facet
        # P_ij runs q_ijk -> c_T -> q_ijl, q_ijk on the face opposite slot d.
        i = St[:, _EVEN[:, 0]]
        j = St[:, _EVEN[:, 1]]
        Pi, Pj = P[i], P[j]
        xx = x[:, None, :]
        e = 0.5 * (Pj - xx)
        A = 0.5 * (xx + Pi)
        dq = Q[:, _EVEN[:, 3]] - Q[:, _EVEN[:, 2]]
        vol = _triple(e, dq, c[:, None, :] - A)
        key_rows = [np.repeat(qi, 12)]
        key_cols = [i.ravel()]
        key_vals = [vol.ravel()]
        # Cut pieces along the plane between x and i, split at h_ij.
        bd = ~inner
        if bd.any():
            pb, mb = np.nonzero(bd)
            Sb = St[pb]
            rows6 = np.arange(len(pb))[:, None]
            i = Sb[rows6, _BPAIR_A[mb]]
            j = Sb[rows6, _BPAIR_B[mb]]
            sign = _BPAIR_S[mb]
            xb = x[pb][:, None, :]
            u = P[i] - xb
            v = P[j] - xb
            w = _cross(u, v)
            ww = (w * w).sum(axis=2)
            h = xb + ((u * u).sum(axis=2)[..., None] * _cross(v, w) + (v * v).sum(axis=2)[..., None] * _cross(w, u)) / (
                2.0 * ww[..., None]
            )
            A = xb + 0.5 * u
            e = 0.5 * v
            g = Q[pb, mb][:, None, :]
            vol = sign * _triple(e, h - A, g - A)
            key_rows.append(np.repeat(qi[pb], 6))
            key_cols.append(i.ravel())
            key_vals.append(vol.ravel())
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
    corners = np.array([[(lo, hi)[a][0], (lo, hi)[b][1], (lo, hi)[c][2]] for a in (0, 1) for b in (0, 1) for c in (0, 1)])
    faces = []
    for axis in range(3):
        for end in (lo, hi):
            f = mid.copy()
            f[axis] = end[axis]
            faces.append(f)
    return np.vstack([corners, np.array(faces)])
