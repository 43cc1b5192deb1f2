"""NURBS static parts: the skull cap that no FAP moves, as a trimmed tensor-product NURBS surface.

The parts of the head that only the head rotation moves (the forehead above the brows'
reach, the top and back of the skull) carry no animation, so they can be any surface; the
triangle head is coarse there (edges ~11 mm) and looks faceted. This module replaces them
by a smooth surface joined to the triangles of the moving regions without cracks:

* **Region** (:func:`static_region`): the skin triangles whose three corners have no
  feature-point weight, no jaw share and no lid share in the rig (and lie above the nape,
  :data:`FLOOR_POINT`), cut to the edge-connected piece under the top of the head (11.4)
  and cleaned until every boundary vertex has one boundary edge in and one out (each
  border a simple loop), and kept mirror-symmetric (by the mirror table).
* **Chart**: spherical angles about a centre inside the skull, ``alpha`` round the
  left-right axis (front, top, back) and ``beta`` its latitude toward the ears; the
  region is star-shaped from there (every region triangle keeps its orientation in the
  chart, checked). ``u`` is ``alpha`` and ``v`` is ``-beta``, both scaled to [0, 1], so that
  the surface normal ``S_u x S_v`` points out of the head and the mirror is ``v -> 1 - v``.
* **Fit** (:func:`fit_static_parts`, :func:`fit_surface`): the radius of the region's vertices (and one ring of
  their neighbours, so the surface continues across the border) interpolated by a thin-plate
  spline onto a regular (u, v) grid, symmetrised, and approximated by least squares with a
  degree-3 tensor-product surface (a geomdl ``NURBS.Surface``, unit weights, uniform clamped
  knots, :data:`CONTROL_POINTS`): the basis functions are geomdl's (``helpers.find_spans``,
  ``helpers.basis_functions``); surface points are geomdl's ``evaluate_list`` (the foot-point
  iterations sum geomdl's basis functions over the control net in one numpy contraction, a few
  times faster, checked against it); the fit error is the distance of each original vertex to
  the surface (Gauss-Newton foot points).
* **Trims**: the region's border loops mapped to (u, v), the outer one counter-clockwise and
  holes clockwise (signed area checked and fixed), also set as degree-1 geomdl trim curves.
* **Tessellation** (:func:`nurbs_head`): samples about :data:`SPACING_MM` apart on the
  surface (mirror-symmetric rows), the border loop's own vertices and the static feature
  points (11.x) triangulated by Delaunay in a conformal (Mercator) chart; samples are kept
  out of every border edge's diametral circle, and a border edge that other border vertices
  still hide is forced in (the two pseudo-polygons it cuts re-triangulated), so that every
  border edge is a triangle edge (checked). The border vertices *are* the moving region's vertices (same index, same
  position: the boundary mapping), so the seam has no crack; within :data:`BLEND_MM` of the
  border the surface is blended toward the triangles it replaces (smoothstep in the distance
  to the seam), so that the seam has no step and no crease either.

The result is a :class:`~mpeg4fa.face.mesh.HeadMesh` whose skin is the moving triangles plus
the NURBS tessellation; the other parts, feature points, joints and mirror table are remapped.
It is built on demand (about 0.35 s on the generic head), not cached.

>>> face = FaceModel.default()
>>> smooth = FaceModel(nurbs_head(face.mesh, face.rig))   # ~0.4 s
>>> parts = fit_static_parts(face.mesh, face.rig)         # the surface, its trims, the fit error
>>> compare_silhouettes(face.mesh, smooth.mesh)           # per view: area fraction, max mm
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from matplotlib.path import Path as Polygon
from scipy.interpolate import RBFInterpolator
from scipy.sparse.csgraph import connected_components
from scipy.spatial import Delaunay, cKDTree

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import FaceUnits, HeadMesh

DEGREE = 3
CONTROL_POINTS = (24, 24)  # (u, v) control points of the skull surface
FIT_GRID = 72  # samples per direction of the resampled radius the surface is fitted to
SPACING_MM = 6.0  # tessellation sample spacing on the surface (the triangle head's skull edges are ~11 mm)
BLEND_MM = 12.0  # within this distance of the seam the surface is blended toward the mesh
UV_SEAM_JUMP = 0.02  # corners' texture coordinates further apart than this: the triangle is on a UV seam
CHART_MARGIN = 0.08  # the chart's rectangle exceeds the region by this fraction of its extent
RBF_SMOOTHING = 2.0  # thin-plate smoothing of the radius (mm^2 scale): irons out the mesh's facets
FLOOR_POINT = "7.1"  # the region stays above this feature point's height (the nape)
TOP_POINT = "11.4"  # the region is the piece of static skin under this point
VERSION = 1  # bump when the construction changes (named in the head's source)

_BOUNDARY_CLEAR = 0.5  # samples keep this many local spacings from the border
_GABRIEL_SLACK = 1.08  # and out of each border edge's diametral circle enlarged by this


# -- the parts -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Chart:
    """Spherical angles about ``centre``, scaled to the unit square (see the module doc)."""

    centre: np.ndarray  # (3,)
    alpha: tuple[float, float]  # range of alpha (rad) mapped to u = 0..1
    beta: float  # |beta| (rad) mapped to v = 1..0 (v = 0.5 on the midline)
    radius: float  # mean radius of the region (mm), the chart's length scale

    def angles(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(alpha, beta, radius) of points."""
        d = np.asarray(points, float) - self.centre
        r = np.linalg.norm(d, axis=1)
        alpha = np.arctan2(d[:, 1], d[:, 2])
        alpha = np.where(alpha < -np.pi / 2, alpha + 2 * np.pi, alpha)  # the cut runs under the chin
        beta = np.arcsin(np.clip(d[:, 0] / r, -1.0, 1.0))
        return alpha, beta, r

    def uv(self, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
        a0, a1 = self.alpha
        return np.c_[(alpha - a0) / (a1 - a0), 0.5 - 0.5 * beta / self.beta]

    def from_uv(self, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a0, a1 = self.alpha
        uv = np.asarray(uv, float)
        return a0 + uv[:, 0] * (a1 - a0), (0.5 - uv[:, 1]) * 2.0 * self.beta

    def direction(self, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
        return np.c_[np.sin(beta), np.cos(beta) * np.sin(alpha), np.cos(beta) * np.cos(alpha)]

    def mercator(self, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
        """Conformal plane coordinates (mm at the midline), oriented like (u, v)."""
        return self.radius * np.c_[alpha, -np.arctanh(np.sin(beta))]


@dataclass(frozen=True)
class NurbsPart:
    """One trimmed NURBS surface replacing a static region of the skin."""

    name: str
    surface: object  # geomdl.NURBS.Surface (trims set)
    chart: Chart
    trims: tuple[np.ndarray, ...]  # closed (u, v) polylines (no repeated end point): outer CCW, then holes CW
    trim_vertices: tuple[np.ndarray, ...]  # the mesh vertex of each trim point
    region_triangles: np.ndarray  # (T,) rows of mesh.triangles["skin"] the surface replaces
    interior: np.ndarray  # mesh vertices only those triangles use (removed from the skin)
    symmetric: bool  # the mesh is mirror-symmetric (then the surface and tessellation are made exactly so)
    fit_rms_mm: float  # distance of the region's original vertices to the surface
    fit_max_mm: float
    fit_seconds: float


@dataclass(frozen=True)
class NurbsParts:
    """The static parts of one head as NURBS surfaces (one, the skull cap, for the MPEG-4 heads)."""

    parts: tuple[NurbsPart, ...]
    static: np.ndarray  # (V,) bool: skin vertices no FAP moves (before the region is cut and cleaned)


# -- the static region -----------------------------------------------------------------------------

def is_symmetric(mesh: HeadMesh, *, tol_mm: float = 1e-9) -> bool:
    """Whether the skin is its own mirror image through its mirror table about x = 0 (the generic
    and procedural heads are, bit for bit; a calibrated head usually is not)."""
    skin = mesh.part("skin")
    v = mesh.vertices
    return bool(np.abs(v[mesh.mirror[skin]] * [-1.0, 1.0, 1.0] - v[skin]).max() <= tol_mm)


def static_vertices(mesh: HeadMesh, rig) -> np.ndarray:
    """``(V,)`` bool: skin vertices that no FAP moves except the head rotation."""
    out = np.zeros(mesh.n_vertices, bool)
    out[mesh.part("skin")] = True
    out[rig.moving] = False
    out[rig.jaw_rows[0]] = False
    for sheet in rig.lids.values():
        out[sheet.rows] = False
    for rows, _, _ in rig.roll_rows.values():
        out[rows] = False
    return out & out[mesh.mirror]


def _directed_edges(tri: np.ndarray) -> np.ndarray:
    return np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])


def _edge_keys(edges: np.ndarray, n: int) -> np.ndarray:
    return edges[:, 0].astype(np.int64) * n + edges[:, 1]


def _boundary_edges(tri: np.ndarray, n: int) -> np.ndarray:
    """Directed edges of ``tri`` whose reverse is not an edge of ``tri`` (the border, as wound)."""
    e = _directed_edges(tri)
    keys = _edge_keys(e, n)
    rev = _edge_keys(e[:, ::-1], n)
    return e[~np.isin(rev, keys)]


def _edge_components(tri: np.ndarray, n: int) -> np.ndarray:
    """Label of each triangle's edge-connected component."""
    e = np.sort(_directed_edges(tri), axis=1)
    keys = _edge_keys(e, n)
    _, edge_id = np.unique(keys, return_inverse=True)
    t = np.tile(np.arange(len(tri)), 3)
    inc = sp.csr_matrix((np.ones(len(t)), (t, edge_id)), shape=(len(tri), edge_id.max() + 1))
    _, labels = connected_components(inc @ inc.T, directed=False)
    return labels


def static_region(mesh: HeadMesh, static: np.ndarray) -> np.ndarray:
    """Rows of the skin triangles forming a clean static region under :data:`TOP_POINT`.

    Clean: one edge-connected piece, off the mesh's own border (the neck cut), and every
    border vertex on exactly one border loop (no two loops touch, no loop touches itself).
    """
    tri = np.asarray(mesh.triangles["skin"], np.int64)
    n = mesh.n_vertices
    v = mesh.vertices
    floor = mesh.fp(FLOOR_POINT)[1] if FLOOR_POINT in mesh.fp_labels else -np.inf
    above = np.minimum(v[:, 1], v[mesh.mirror, 1]) >= floor  # per mirror pair: the region stays symmetric
    ok = static[tri].all(axis=1) & above[tri].all(axis=1)
    top = mesh.fp_vertex[mesh.fp_index(TOP_POINT)]
    mesh_border = _boundary_edges(tri, n)
    border_keys = _edge_keys(mesh_border, n)
    for _ in range(50):
        rows = np.flatnonzero(ok)
        if not len(rows):
            break
        labels = _edge_components(tri[rows], n)
        at_top = np.flatnonzero((tri[rows] == top).any(axis=1))
        if not len(at_top):
            raise FaceError(f"the top of the head ({TOP_POINT}) is not in the static skin",
                            hint="the rig moves it: no NURBS skull for this head")
        keep = labels == labels[at_top[0]]
        ok[:] = False
        ok[rows[keep]] = True
        region = tri[ok]
        border = _boundary_edges(region, n)
        outgoing = np.bincount(border[:, 0], minlength=n)
        bad = outgoing > 1
        bad[border[np.isin(_edge_keys(border, n), border_keys)].ravel()] = True  # on the neck cut
        if not bad.any():
            return np.flatnonzero(ok)
        ok &= ~bad[tri].any(axis=1)
    raise FaceError("the static skin has no clean region with simple border loops",
                    hint="the rig's moving region leaves no skull cap")


def border_loops(region: np.ndarray, n: int) -> list[np.ndarray]:
    """The region's border as closed vertex loops, each wound as its triangles are."""
    border = _boundary_edges(region, n)
    nxt = dict(zip(border[:, 0].tolist(), border[:, 1].tolist()))
    loops, seen = [], set()
    for start in border[:, 0].tolist():
        if start in seen:
            continue
        loop, a = [], start
        while a not in seen:
            seen.add(a)
            loop.append(a)
            a = nxt[a]
        loops.append(np.array(loop, np.int64))
    return loops


def signed_area(loop: np.ndarray) -> float:
    """Shoelace area of a closed 2-D polyline: > 0 counter-clockwise."""
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def orient_trims(loops: list[np.ndarray]) -> tuple[list[int], list[bool]]:
    """How to order and wind closed (u, v) loops as trims: the largest (by area) first and
    counter-clockwise, the holes after it clockwise. Returns the order and, per loop in that
    order, whether it must be reversed."""
    areas = [signed_area(np.asarray(lp, float)) for lp in loops]
    order = sorted(range(len(loops)), key=lambda k: -abs(areas[k]))
    return order, [(areas[k] > 0) != (rank == 0) for rank, k in enumerate(order)]


def _tri_area(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


# -- the fit ---------------------------------------------------------------------------------------

def _basis(knots, n_ctrl: int, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knot spans ``(N,)`` and the ``DEGREE + 1`` non-zero basis values ``(N, DEGREE + 1)`` at each
    parameter (geomdl's span search and Cox-de Boor basis)."""
    from geomdl import helpers

    t = np.clip(np.asarray(params, float), 0.0, 1.0).tolist()
    spans = helpers.find_spans(DEGREE, list(knots), n_ctrl, t)
    return np.asarray(spans, np.int64), np.asarray(helpers.basis_functions(DEGREE, list(knots), spans, t), float)


def _collocation(knots, n_ctrl: int, params: np.ndarray) -> np.ndarray:
    """``(len(params), n_ctrl)`` B-spline basis matrix (the least-squares fit's design matrix)."""
    spans, basis = _basis(knots, n_ctrl, params)
    out = np.zeros((len(params), n_ctrl))
    cols = spans[:, None] - DEGREE + np.arange(DEGREE + 1)
    np.put_along_axis(out, cols, basis, axis=1)
    return out


def _make_surface(ctrl: np.ndarray):
    from geomdl import NURBS, knotvector

    nu, nv = ctrl.shape[:2]
    s = NURBS.Surface()
    s.degree_u = s.degree_v = DEGREE
    s.ctrlpts_size_u, s.ctrlpts_size_v = nu, nv
    s.ctrlpts = ctrl.reshape(-1, 3).tolist()  # geomdl order: v runs fastest
    s.knotvector_u = knotvector.generate(DEGREE, nu)
    s.knotvector_v = knotvector.generate(DEGREE, nv)
    return s


def evaluate(surface, uv: np.ndarray, *, fast: bool = False) -> np.ndarray:
    """Surface points at ``(N, 2)`` parameters: geomdl's ``evaluate_list`` (~0.1 ms a point in pure
    Python), or with ``fast`` geomdl's basis functions summed over the control net in one numpy
    contraction (the foot-point iterations; the tests check the two agree to 1e-9 mm)."""
    uv = np.clip(np.asarray(uv, float).reshape(-1, 2), 0.0, 1.0)
    if not len(uv):
        return np.zeros((0, 3))
    if not fast:
        return np.asarray(surface.evaluate_list(uv.tolist()), float)
    nu, nv = surface.ctrlpts_size_u, surface.ctrlpts_size_v
    w = np.asarray(surface.weights, float).reshape(nu, nv, 1)
    cw = np.c_[np.asarray(surface.ctrlpts, float).reshape(nu * nv, 3) * w.reshape(-1, 1), w.reshape(-1, 1)]
    cw = cw.reshape(nu, nv, 4)
    su, bu = _basis(surface.knotvector_u, nu, uv[:, 0])
    sv, bv = _basis(surface.knotvector_v, nv, uv[:, 1])
    iu = su[:, None] - DEGREE + np.arange(DEGREE + 1)
    iv = sv[:, None] - DEGREE + np.arange(DEGREE + 1)
    h = np.einsum("na,nb,nabd->nd", bu, bv, cw[iu[:, :, None], iv[:, None, :]])
    return h[:, :3] / h[:, 3:]


def surface_distance(surface, points: np.ndarray, uv0: np.ndarray, *, steps: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Distance of each point to the surface and its foot's (u, v): Gauss-Newton from ``uv0``, the
    Jacobian by differences of geomdl evaluations (one batched call per step)."""
    uv = np.clip(np.asarray(uv0, float).copy(), 0.0, 1.0)
    pts = np.asarray(points, float)
    eps = 1e-6
    for _ in range(steps):
        du = np.where(uv[:, :1] > 0.5, -eps, eps)
        dv = np.where(uv[:, 1:] > 0.5, -eps, eps)
        probe = np.vstack([uv, uv + np.c_[du, np.zeros_like(du)], uv + np.c_[np.zeros_like(dv), dv]])
        val = evaluate(surface, probe, fast=True).reshape(3, len(uv), 3)
        s, su, sv = val[0], (val[1] - val[0]) / du, (val[2] - val[0]) / dv
        # normal equations of the 2x2 least squares, all points at once
        a, b, c = np.einsum("nd,nd->n", su, su), np.einsum("nd,nd->n", su, sv), np.einsum("nd,nd->n", sv, sv)
        r = pts - s
        ru, rv = np.einsum("nd,nd->n", su, r), np.einsum("nd,nd->n", sv, r)
        det = np.maximum(a * c - b * b, 1e-300)
        uv = np.clip(uv + np.c_[(c * ru - b * rv) / det, (a * rv - b * ru) / det], 0.0, 1.0)
    return np.linalg.norm(evaluate(surface, uv, fast=True) - pts, axis=1), uv


def _chart(points: np.ndarray, centre: np.ndarray) -> Chart:
    probe = Chart(centre, (0.0, 1.0), 1.0, 1.0)
    alpha, beta, r = probe.angles(points)
    a0, a1 = alpha.min(), alpha.max()
    pad = CHART_MARGIN * (a1 - a0)
    b = np.abs(beta).max() * (1.0 + CHART_MARGIN)
    if b >= np.pi / 2 * 0.95:
        raise FaceError("the static region reaches the chart's poles (the ears' axis)",
                        hint="the region is not a skull cap")
    return Chart(centre, (float(a0 - pad), float(a1 + pad)), float(b), float(r.mean()))


def fit_surface(chart: Chart, points: np.ndarray, control_points: tuple[int, int] = CONTROL_POINTS, *,
                symmetric: bool = True):
    """A degree-3 B-spline surface (a geomdl NURBS with unit weights) through ``points`` over ``chart``.

    The radius of the points about the chart's centre is interpolated (thin-plate spline) onto a
    regular (u, v) grid and the grid's 3-D points are fitted by separable least squares on geomdl's
    basis functions (uniform clamped knots). With ``symmetric`` (a mirror-symmetric head) the grid
    and the control net are symmetrised so that the surface is exactly so (v -> 1 - v, x -> -x)."""
    from geomdl import knotvector

    a_d, b_d, r_d = chart.angles(points)
    scale = chart.radius
    rbf = RBFInterpolator(np.c_[a_d * scale, b_d * scale], r_d, kernel="thin_plate_spline",
                          smoothing=RBF_SMOOTHING, degree=1)
    g = np.linspace(0.0, 1.0, FIT_GRID)
    g = 0.5 * (g + (1.0 - g[::-1]))  # exactly symmetric about 0.5
    uu, vv = np.meshgrid(g, g, indexing="ij")
    ga, gb = chart.from_uv(np.c_[uu.ravel(), vv.ravel()])
    radius = rbf(np.c_[ga * scale, gb * scale]).reshape(FIT_GRID, FIT_GRID)
    gb = gb.reshape(FIT_GRID, FIT_GRID)
    if symmetric:
        radius = 0.5 * (radius + radius[:, ::-1])
        gb = 0.5 * (gb - gb[:, ::-1])
    grid = chart.centre + radius.reshape(-1, 1) * chart.direction(ga, gb.ravel())
    grid = grid.reshape(FIT_GRID, FIT_GRID, 3)
    nu, nv = control_points
    cu = _collocation(knotvector.generate(DEGREE, nu), nu, g)
    cv = _collocation(knotvector.generate(DEGREE, nv), nv, g)
    # separable least squares: grid = Cu @ P @ Cv^T per coordinate
    step, *_ = np.linalg.lstsq(cu, grid.reshape(FIT_GRID, -1), rcond=None)  # (nu, G*3)
    step = step.reshape(nu, FIT_GRID, 3).transpose(1, 0, 2).reshape(FIT_GRID, -1)
    ctrl, *_ = np.linalg.lstsq(cv, step, rcond=None)  # (nv, nu*3)
    ctrl = ctrl.reshape(nv, nu, 3).transpose(1, 0, 2)
    if symmetric:
        flip = np.array([-1.0, 1.0, 1.0])
        ctrl = chart.centre + 0.5 * ((ctrl - chart.centre) + (ctrl[:, ::-1] - chart.centre) * flip)
    return _make_surface(ctrl)


def fit_static_parts(mesh: HeadMesh, rig, *, control_points: tuple[int, int] = CONTROL_POINTS,
                     static: np.ndarray | None = None) -> NurbsParts:
    """The skull cap of ``mesh`` (no FAP of ``rig`` moves it) fitted with a trimmed NURBS surface.

    ``static`` overrides which vertices count as static (default :func:`static_vertices`): a
    moving island inside the cap becomes a hole of the trim."""
    from geomdl import BSpline, knotvector

    t0 = time.perf_counter()
    n = mesh.n_vertices
    v = mesh.vertices
    tri = np.asarray(mesh.triangles["skin"], np.int64)
    static = static_vertices(mesh, rig) if static is None else np.asarray(static, bool)
    rows = static_region(mesh, static)
    region = tri[rows]
    used = np.unique(region)
    loops = border_loops(region, n)
    on_border = np.unique(np.concatenate(loops))
    interior = np.setdiff1d(used, on_border)
    # the centre: the middle of the region's box (on the midline x = 0 of a symmetric head)
    lo, hi = v[used].min(axis=0), v[used].max(axis=0)
    centre = (lo + hi) / 2
    symmetric = is_symmetric(mesh)
    chart = _chart(v[used], centre)
    alpha, beta, _ = chart.angles(v)
    uv_all = chart.uv(alpha, beta)
    area = _tri_area(uv_all, region)
    if not (area > 0).all():
        raise FaceError(f"{int((area <= 0).sum())} of {len(region)} static triangles fold in the skull chart",
                        where="nurbs", hint="the region is not star-shaped about its centre")
    # data: the region's vertices and one ring of neighbours (the surface runs on across the seam)
    near = np.unique(tri[np.isin(tri, used).any(axis=1)])
    near = near[np.abs(beta[near]) < chart.beta]
    surface = fit_surface(chart, v[near], control_points, symmetric=symmetric)

    # trims: the border loops in (u, v), outer counter-clockwise, holes clockwise
    order, flip = orient_trims([uv_all[lp] for lp in loops])
    trims, trim_vertices, curves = [], [], []
    for k, (j, reverse) in enumerate(zip(order, flip)):
        lp = loops[j][::-1] if reverse else loops[j]
        pts = uv_all[lp]
        want_ccw = k == 0
        trims.append(pts)
        trim_vertices.append(lp)
        crv = BSpline.Curve()
        crv.degree = 1
        crv.ctrlpts = np.vstack([pts, pts[:1]]).tolist()
        crv.knotvector = knotvector.generate(1, len(pts) + 1)
        crv.opt = ["reversed", 1 if want_ccw else 0]  # geomdl: 1 keeps the inside (its sense of a CCW loop)
        curves.append(crv)
    surface.trims = curves

    dist, _ = surface_distance(surface, v[used], uv_all[used])
    part = NurbsPart(
        name="skull", surface=surface, chart=chart, trims=tuple(trims), trim_vertices=tuple(trim_vertices),
        region_triangles=rows, interior=interior, symmetric=symmetric, fit_rms_mm=float(np.sqrt(np.mean(dist ** 2))),
        fit_max_mm=float(dist.max()), fit_seconds=time.perf_counter() - t0)
    return NurbsParts(parts=(part,), static=static)


# -- the tessellation ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Tessellation:
    """A NURBS part as triangles: new vertices, and triangles over (new + border) vertices."""

    points: np.ndarray  # (N, 3) new vertices
    uv: np.ndarray  # (N, 2) their surface parameters
    mirror: np.ndarray  # (N,) index of each new vertex's mirror image among the new ones
    triangles: np.ndarray  # (T, 3): index < 0 is border vertex ~index (mesh numbering), else a new vertex
    forced: dict[int, int]  # mesh vertex of a static feature point inside the region -> its new vertex


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(len(p),)`` distance of each point to the nearest of the segments a[k]-b[k]."""
    out = np.full(len(p), np.inf)
    for k0 in range(0, len(a), 256):
        aa, bb = a[k0:k0 + 256], b[k0:k0 + 256]
        ab = bb - aa
        t = np.einsum("pkd,kd->pk", p[:, None, :] - aa[None], ab) / np.maximum(np.einsum("kd,kd->k", ab, ab), 1e-300)
        foot = aa[None] + np.clip(t, 0.0, 1.0)[..., None] * ab[None]
        out = np.minimum(out, np.linalg.norm(p[:, None, :] - foot, axis=2).min(axis=1))
    return out


def _inside(polys: list[np.ndarray], pts: np.ndarray) -> np.ndarray:
    """Inside the outer loop and outside every hole."""
    inside = Polygon(polys[0]).contains_points(pts)
    for hole in polys[1:]:
        inside &= ~Polygon(hole).contains_points(pts)
    return inside


def _cross2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _pseudo_polygon(pts: np.ndarray, chain: list[int]) -> list[tuple[int, int, int]]:
    """Triangles filling the pseudo-polygon ``chain`` (its first and last vertex the base edge),
    each split at the chain vertex that sees the base under the largest angle (the Delaunay one)."""
    if len(chain) < 3:
        return []
    p, q = pts[chain[0]], pts[chain[-1]]
    inner = np.array(chain[1:-1])
    u, w = p - pts[inner], q - pts[inner]
    angle = np.arctan2(np.abs(_cross2(u, w)), np.einsum("kd,kd->k", u, w))
    k = int(np.argmax(angle)) + 1
    return ([(chain[0], chain[k], chain[-1])] + _pseudo_polygon(pts, chain[:k + 1])
            + _pseudo_polygon(pts, chain[k:]))


def _recover_edges(pts: np.ndarray, simp: np.ndarray, edges: list[tuple[int, int]]) -> np.ndarray:
    """Force ``edges`` into a triangulation: the triangles a missing edge crosses are replaced by
    the two pseudo-polygons on either side of it, each re-triangulated (constrained Delaunay, locally)."""
    for a, b in edges:
        pa, pb = pts[a], pts[b]
        d = pb - pa
        e = np.concatenate([simp[:, [0, 1]], simp[:, [1, 2]], simp[:, [2, 0]]])
        tri_of = np.tile(np.arange(len(simp)), 3)
        s0, s1 = _cross2(d, pts[e[:, 0]] - pa), _cross2(d, pts[e[:, 1]] - pa)
        r = pts[e[:, 1]] - pts[e[:, 0]]
        t0, t1 = _cross2(r, pa - pts[e[:, 0]]), _cross2(r, pb - pts[e[:, 0]])
        crossed = (s0 * s1 < 0) & (t0 * t1 < 0)
        if not crossed.any():
            continue
        q = pts - pa
        along = q @ d / (d @ d)
        on = (np.abs(_cross2(d, q)) <= 1e-12 * (d @ d)) & (along > 1e-9) & (along < 1.0 - 1e-9)
        if on.any():
            raise FaceError("a tessellation vertex lies on a seam edge", where="nurbs",
                            hint="try another spacing_mm")
        ce = e[crossed]
        denom = _cross2(d, r[crossed])
        t = _cross2(pts[ce[:, 0]] - pa, r[crossed]) / denom  # where along a-b each crossed edge is met
        order = np.argsort(t, kind="stable")
        left = np.where(s0[crossed][:, None] > 0, ce, ce[:, ::-1])  # (left endpoint, right endpoint)
        chains = []
        for side in (0, 1):
            chain = [a]
            for v in left[order, side].tolist():
                if v != chain[-1]:
                    chain.append(v)
            chains.append(chain + [b])
        simp = np.delete(simp, np.unique(tri_of[crossed]), axis=0)
        new = _pseudo_polygon(pts, chains[0]) + _pseudo_polygon(pts, chains[1])
        simp = np.vstack([simp, np.array(new, simp.dtype).reshape(-1, 3)])
    return simp


def tessellate(mesh: HeadMesh, part: NurbsPart, *, spacing_mm: float = SPACING_MM,
               forced_vertices: np.ndarray | None = None) -> Tessellation:
    """Triangles of ``part``: samples ~``spacing_mm`` apart inside its trims, plus its border vertices
    and ``forced_vertices`` (mesh vertices inside the region that must become vertices: the static
    feature points, each at the surface point of its own (u, v))."""
    chart = part.chart
    v = mesh.vertices
    border = np.concatenate(part.trim_vertices)
    b_alpha, b_beta, _ = chart.angles(v[border])
    b_m = chart.mercator(b_alpha, b_beta)
    polys, k0 = [], 0
    for lp in part.trim_vertices:
        polys.append(b_m[k0:k0 + len(lp)])
        k0 += len(lp)
    a_lo, a_hi = b_alpha.min(), b_alpha.max()
    b_max = np.abs(b_beta).max()
    # mirror-symmetric rows: beta = k * h / R, alpha steps h / (R cos beta), odd rows offset by half a step
    h = spacing_mm / chart.radius
    rows = np.arange(0, int(np.ceil(b_max / h)) + 1)
    alphas, betas = [], []
    for k in rows:
        beta = k * h
        da = h / np.cos(beta)
        a = np.arange(a_lo - da * (0.5 * (k % 2)), a_hi + da, da)
        for sign in ((1.0,) if k == 0 else (1.0, -1.0)):
            alphas.append(a)
            betas.append(np.full(len(a), sign * beta))
    s_alpha, s_beta = np.concatenate(alphas), np.concatenate(betas)
    forced = np.zeros(0, np.int64) if forced_vertices is None else np.asarray(forced_vertices, np.int64)
    f_alpha, f_beta, _ = chart.angles(v[forced]) if len(forced) else (np.zeros(0), np.zeros(0), None)
    s_m = chart.mercator(s_alpha, s_beta)
    local = spacing_mm / np.cos(s_beta)  # the sample spacing in the Mercator plane
    keep = _inside(polys, s_m)
    seg_a = np.concatenate([p for p in polys])
    seg_b = np.concatenate([np.roll(p, -1, axis=0) for p in polys])
    clear = _BOUNDARY_CLEAR
    for attempt in range(4):
        ok = keep & (_segment_distance(s_m, seg_a, seg_b) > clear * local)
        mid, half = 0.5 * (seg_a + seg_b), 0.5 * np.linalg.norm(seg_b - seg_a, axis=1) * _GABRIEL_SLACK
        for ball in cKDTree(s_m).query_ball_point(mid, half):
            ok[ball] = False
        if len(forced):
            f_m = chart.mercator(f_alpha, f_beta)
            d = cKDTree(f_m).query(s_m)[0]
            ok &= d > 0.5 * local
        else:
            f_m = np.zeros((0, 2))
        pts_m = np.vstack([b_m, f_m, s_m[ok]])
        simp = Delaunay(pts_m).simplices
        # every border edge must be a triangle edge (then the seam is exactly the mesh's): the samples
        # keep out of their diametral circles; edges that other border vertices hide are forced in
        want, k0 = [], 0
        for lp in part.trim_vertices:
            idx = np.arange(k0, k0 + len(lp))
            want += [tuple(sorted(e)) for e in zip(idx.tolist(), np.roll(idx, -1).tolist())]
            k0 += len(lp)
        have = set(map(tuple, np.sort(_directed_edges(simp), axis=1).tolist()))
        simp = _recover_edges(pts_m, simp, [e for e in want if e not in have])
        simp = simp[_inside(polys, pts_m[simp].mean(axis=1))]
        have = set(map(tuple, np.sort(_directed_edges(simp), axis=1).tolist()))
        missing = [e for e in want if e not in have]
        if not missing:
            break
        clear *= 1.5
    else:
        raise FaceError(f"{len(missing)} seam edges are not in the NURBS tessellation", where="nurbs",
                        hint="try another spacing_mm")
    area = _tri_area(pts_m, simp)
    simp = np.where((area < 0)[:, None], simp[:, [0, 2, 1]], simp)
    # new vertices: forced points and samples, evaluated on the surface
    n_b = len(b_m)
    new_alpha = np.r_[f_alpha, s_alpha[ok]]
    new_beta = np.r_[f_beta, s_beta[ok]]
    uv = chart.uv(new_alpha, new_beta)
    pts = evaluate(part.surface, uv)
    # the blend: near the seam the surface gives way to the triangles it replaces (the point of the
    # replaced triangle under each sample), so that the seam has neither a step nor a crease
    new_m = pts_m[n_b:]
    rows, lam = _locate(mesh, part, new_m)
    corners = v[np.asarray(mesh.triangles["skin"], np.int64)[part.region_triangles[rows]]]
    target = np.einsum("nj,njd->nd", lam, corners)
    dist_mm = _segment_distance(new_m, seg_a, seg_b) * np.cos(new_beta)
    x = np.clip(dist_mm / BLEND_MM, 0.0, 1.0)
    fade = 1.0 - x * x * (3.0 - 2.0 * x)
    pts = pts + fade[:, None] * (target - pts)
    # the mirror among the new vertices: samples pair up by construction (rows at +-beta; on an
    # asymmetric head, whose trims differ left and right, with the nearest mirrored sample), the
    # forced points as their mesh vertices do
    n_f = len(forced)
    samples_m = new_m[n_f:]
    dm, pair = cKDTree(samples_m).query(samples_m * np.array([1.0, -1.0]))
    if part.symmetric and len(dm) and dm.max() > 1e-6 * chart.radius:
        raise FaceError("the NURBS samples of a symmetric head are not mirror-symmetric", where="nurbs")
    slot = {int(f): i for i, f in enumerate(forced)}
    forced_pair = [slot.get(int(mesh.mirror[f]), i) for i, f in enumerate(forced)]
    mirror = np.r_[np.array(forced_pair, np.int64), pair + n_f]
    if part.symmetric:
        centre = chart.centre
        pts = centre + 0.5 * ((pts - centre) + (pts[mirror] - centre) * np.array([-1.0, 1.0, 1.0]))
    tris = np.where(simp < n_b, ~border[np.minimum(simp, n_b - 1)], simp - n_b)
    return Tessellation(points=pts, uv=uv, mirror=mirror, triangles=tris,
                        forced={int(f): i for i, f in enumerate(forced)})


# -- the head --------------------------------------------------------------------------------------

def _barycentric(p: np.ndarray, tri_m: np.ndarray) -> np.ndarray:
    """Barycentric coordinates of points ``p (..., 2)`` in triangles ``tri_m (..., 3, 2)``."""
    e1, e2 = tri_m[..., 1, :] - tri_m[..., 0, :], tri_m[..., 2, :] - tri_m[..., 0, :]
    q = p - tri_m[..., 0, :]
    det = _cross2(e1, e2)
    l1, l2 = _cross2(q, e2) / det, _cross2(e1, q) / det
    return np.stack([1.0 - l1 - l2, l1, l2], axis=-1)


def _locate(mesh: HeadMesh, part: NurbsPart, points_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The replaced triangle under each chart point (index into ``part.region_triangles``) and the
    point's barycentric coordinates in it (extended slightly outside where the chart's curved edges
    leave a point in no triangle)."""
    old = np.asarray(mesh.triangles["skin"], np.int64)[part.region_triangles]
    a, b, _ = part.chart.angles(mesh.vertices)
    old_m = part.chart.mercator(a, b)[old]  # (T, 3, 2)
    k = min(12, len(old))
    _, cand = cKDTree(old_m.mean(axis=1)).query(points_m, k=k)
    cand = cand.reshape(len(points_m), k)
    score = _barycentric(points_m[:, None, :], old_m[cand]).min(axis=-1)
    best = cand[np.arange(len(cand)), score.argmax(axis=1)]
    return best, _barycentric(points_m, old_m[best])


def _corner_uvs(mesh: HeadMesh, part: NurbsPart, corners_m: np.ndarray) -> np.ndarray:
    """Texture coordinates of the new triangles: each corner takes the texture map of the replaced
    triangle under it (continuous across the new triangles); a triangle whose corners land on
    different sides of a UV seam takes the map of the replaced triangle under its centroid for all
    three corners (extended linearly), so that no triangle spans the seam."""
    old_tri = np.asarray(mesh.triangles["skin"], np.int64)[part.region_triangles]
    old_uv = np.asarray(mesh.corner_uvs["skin"])[part.region_triangles]
    a, b, _ = part.chart.angles(mesh.vertices)
    old_m = part.chart.mercator(a, b)[old_tri]  # (T, 3, 2)
    flat = corners_m.reshape(-1, 2)
    under, lam = _locate(mesh, part, flat)
    per_corner = np.einsum("nj,njd->nd", lam, old_uv[under]).reshape(corners_m.shape)
    best, _ = _locate(mesh, part, corners_m.mean(axis=1))
    lam = _barycentric(corners_m, old_m[best][:, None])  # (T, 3 corners, 3)
    per_triangle = np.einsum("tcj,tjd->tcd", lam, old_uv[best])
    split = np.abs(per_corner - per_triangle).max(axis=(1, 2)) > UV_SEAM_JUMP
    return np.where(split[:, None, None], per_triangle, per_corner)


def build_nurbs_head(mesh: HeadMesh, parts: NurbsParts, *, spacing_mm: float = SPACING_MM) -> HeadMesh:
    """``mesh`` with each NURBS part's region replaced by its tessellation (see the module doc)."""
    skin = mesh.part("skin")
    n = mesh.n_vertices
    removed = np.zeros(n, bool)
    drop_tris = np.zeros(len(mesh.triangles["skin"]), bool)
    new_points, new_mirror, new_tris, new_uvs, fp_new = [], [], [], [], {}
    n_new = 0
    for part in parts.parts:
        interior_fp = np.intersect1d(mesh.fp_vertex, part.interior)
        tess = tessellate(mesh, part, spacing_mm=spacing_mm, forced_vertices=interior_fp)
        a, b, _ = part.chart.angles(mesh.vertices)
        m_old = part.chart.mercator(a, b)
        m_new = part.chart.mercator(*part.chart.from_uv(tess.uv))
        corner_m = np.where((tess.triangles < 0)[..., None], m_old[~np.minimum(tess.triangles, -1)],
                            m_new[np.maximum(tess.triangles, 0)])
        new_uvs.append(_corner_uvs(mesh, part, corner_m))
        new_tris.append(np.where(tess.triangles < 0, tess.triangles, tess.triangles + n_new))
        new_points.append(tess.points)
        new_mirror.append(tess.mirror + n_new)
        for f, i in tess.forced.items():
            fp_new[f] = i + n_new
        n_new += len(tess.points)
        removed[part.interior] = True
        drop_tris[part.region_triangles] = True
    kept = np.flatnonzero(~removed)
    kept_skin = kept[kept < skin.stop]
    n_kept_skin = len(kept_skin)
    remap = np.full(n, -1, np.int64)
    remap[kept_skin] = np.arange(n_kept_skin)
    rest = kept[kept >= skin.stop]
    remap[rest] = np.arange(len(rest)) + n_kept_skin + n_new
    total = n_kept_skin + n_new + len(rest)

    def new_index(local):  # tessellation numbering -> new mesh numbering
        return np.where(local < 0, remap[~np.minimum(local, -1)], local + n_kept_skin)

    vertices = np.vstack([mesh.vertices[kept_skin], *new_points, mesh.vertices[rest]])
    shift = n_new - int(removed.sum())
    ranges = {}
    for name, (a, b) in mesh.part_ranges.items():
        ranges[name] = (0, b + shift) if name == "skin" else (a + shift, b + shift)
    triangles, corner_uvs = {}, {}
    for name, tri in mesh.triangles.items():
        if name == "skin":
            kept_t = np.asarray(tri, np.int64)[~drop_tris]
            triangles[name] = np.vstack([remap[kept_t]] + [new_index(t) for t in new_tris]).astype(np.int32)
            corner_uvs[name] = np.concatenate([np.asarray(mesh.corner_uvs[name])[~drop_tris], *new_uvs])
        else:
            triangles[name] = remap[np.asarray(tri, np.int64)].astype(np.int32)
            corner_uvs[name] = mesh.corner_uvs[name]
    mirror = np.empty(total, np.int64)
    mirror[remap[kept]] = remap[mesh.mirror[kept]]
    if (remap[mesh.mirror[kept]] < 0).any():
        raise FaceError("the static skull region is not mirror symmetric on this head",
                        hint="keep the triangle skull (--skull triangles)")
    if n_new:
        mirror[n_kept_skin:n_kept_skin + n_new] = np.concatenate(new_mirror) + n_kept_skin
    fp_vertex = np.array([remap[f] if remap[f] >= 0 else fp_new[int(f)] + n_kept_skin for f in mesh.fp_vertex],
                         np.int64)
    old_index = np.full(total, -1, np.int64)
    old_index[remap[kept]] = kept
    units = mesh.face_units
    if units is not None:
        offsets, idx, deltas = [0], [], []
        for k in range(len(units.names)):
            a, b = units.offsets[k], units.offsets[k + 1]
            keep = remap[units.indices[a:b]] >= 0
            idx.append(remap[units.indices[a:b][keep]])
            deltas.append(units.deltas[a:b][keep])
            offsets.append(offsets[-1] + int(keep.sum()))
        units = FaceUnits(units.names, np.array(offsets, units.offsets.dtype), np.concatenate(idx).astype(
            units.indices.dtype), np.concatenate(deltas))
    return HeadMesh(
        vertices=vertices, part_ranges=ranges, triangles=triangles, corner_uvs=corner_uvs, mirror=mirror,
        joints={name: int(remap[i]) for name, i in mesh.joints.items()}, fp_labels=mesh.fp_labels,
        fp_vertex=fp_vertex, fp_reach=mesh.fp_reach, face_units=units,
        source=f"{mesh.source} + NURBS skull (mpeg4fa.face.nurbs v{VERSION})".strip(),
        info={**mesh.info, "nurbs": {p.name: {"fit_rms_mm": p.fit_rms_mm, "fit_max_mm": p.fit_max_mm}
                                     for p in parts.parts},
              "old_index": old_index},  # (not saved) each vertex's index in ``mesh``, -1 for NURBS ones
    )


def nurbs_head(mesh: HeadMesh, rig=None, *, spacing_mm: float = SPACING_MM,
               control_points: tuple[int, int] = CONTROL_POINTS) -> HeadMesh:
    """``mesh`` with its skull cap as a tessellated NURBS surface.

    ``rig`` is the mesh's :class:`~mpeg4fa.face.rig.Rig` (built here when not given): it decides which
    skin no FAP moves. Built each time (about 0.35 s on the generic head): what it depends on (the
    mesh, its rig, the constants here) is too much to key a disk cache on safely.
    """
    if rig is None:
        from mpeg4fa.face.fapu import measure_fapu
        from mpeg4fa.face.rig import build_rig

        fps = mesh.feature_points()
        rig = build_rig(mesh, measure_fapu({label: fps[i] for i, label in enumerate(mesh.fp_labels)}))
    parts = fit_static_parts(mesh, rig, control_points=control_points)
    return build_nurbs_head(mesh, parts, spacing_mm=spacing_mm)


# -- silhouettes -----------------------------------------------------------------------------------

SILHOUETTE_MAX_MM = 3.0
"""Stated tolerance: no silhouette point of the NURBS head is further than this from the triangle
head's (orthographic views below). The difference is the sagitta of the triangle head's longest
skull edges (38 mm on the generic head's crown: 38^2 / (8 x 80 mm) = 2.3 mm), which the smooth
surface rounds out, plus the fit error."""
SILHOUETTE_AREA = 0.01
"""... and the silhouettes' symmetric difference is at most this fraction of the triangle head's."""

SILHOUETTE_VIEWS = {"front": (0.0, 0.0), "side": (90.0, 0.0), "back": (180.0, 0.0),
                    "three-quarter": (30.0, 5.0), "top": (0.0, 90.0)}
"""(yaw, pitch) degrees of the orthographic views the silhouettes are compared in."""


def silhouette(mesh: HeadMesh, view: tuple[float, float], *, mm_per_pixel: float = 0.25,
               box: tuple[float, float, float, float] | None = None,
               parts: tuple[str, ...] = ("skin",)) -> tuple[np.ndarray, tuple[float, float, float, float]]:
    """Binary orthographic silhouette of ``parts`` seen from ``view``, and the (x0, y0, x1, y1) mm box."""
    from PIL import Image, ImageDraw

    yaw, pitch = np.radians(view)
    cy, sy, cp, sp_ = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    turn = np.array([[cy, 0.0, -sy], [0.0, 1.0, 0.0], [sy, 0.0, cy]])  # the head turned so the view looks down -z
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, cp, -sp_], [0.0, sp_, cp]])
    p = mesh.vertices @ (tilt @ turn).T
    tri = mesh.all_triangles(parts)
    xy = p[:, :2]
    if box is None:
        used = np.unique(tri)
        lo, hi = xy[used].min(axis=0) - 5.0, xy[used].max(axis=0) + 5.0
        box = (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1]))
    x0, y0, x1, y1 = box
    w, h = int(np.ceil((x1 - x0) / mm_per_pixel)), int(np.ceil((y1 - y0) / mm_per_pixel))
    pix = np.c_[(xy[:, 0] - x0) / mm_per_pixel, (y1 - xy[:, 1]) / mm_per_pixel]
    img = Image.new("1", (w, h), 0)
    draw = ImageDraw.Draw(img)
    for t in pix[tri].tolist():
        draw.polygon([tuple(c) for c in t], fill=1, outline=1)
    return np.asarray(img, bool), box


@dataclass(frozen=True)
class SilhouetteDifference:
    view: str
    area_fraction: float  # pixels in one silhouette only / pixels in the triangle head's
    max_mm: float  # largest distance from a silhouette-only pixel to the other silhouette (Hausdorff)


def compare_silhouettes(a: HeadMesh, b: HeadMesh, *, mm_per_pixel: float = 0.25,
                        views: dict[str, tuple[float, float]] = SILHOUETTE_VIEWS) -> list[SilhouetteDifference]:
    """How far the silhouettes of two heads differ, per view (``a`` is the reference)."""
    from scipy.ndimage import distance_transform_edt

    out = []
    for name, view in views.items():
        ma, box = silhouette(a, view, mm_per_pixel=mm_per_pixel)
        mb, _ = silhouette(b, view, mm_per_pixel=mm_per_pixel, box=box)
        only = ma ^ mb
        da = distance_transform_edt(~ma)  # distance to a's silhouette
        db = distance_transform_edt(~mb)
        worst = max(float(da[mb].max(initial=0.0)), float(db[ma].max(initial=0.0))) * mm_per_pixel
        out.append(SilhouetteDifference(name, float(only.sum() / max(ma.sum(), 1)), worst))
    return out
