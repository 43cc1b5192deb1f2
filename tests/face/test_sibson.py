"""Sibson (natural-neighbour) coordinates: properties, degeneracies, and an independent reference."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, Delaunay, HalfspaceIntersection

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.sibson import NaturalNeighbours, cage_points, inside_hull, natural_neighbour_weights


def grid_sites(k: int = 4, spacing: float = 1.0, offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    g = np.arange(k) * spacing
    return np.array(np.meshgrid(g, g, g, indexing="ij")).reshape(3, -1).T + np.asarray(offset)


def random_sites(seed: int, n: int = 30) -> np.ndarray:
    pts = np.random.default_rng(seed).random((n, 3))
    return np.vstack([pts, cage_points(pts)])


def reference_weights(sites: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Sibson coordinates by brute force: vol(V_new(x) ∩ V_old(i)) / vol(V_new(x)).

    The stolen region of site i is its old Voronoi cell (half-spaces against every
    other site) cut by the bisector of x and p_i, built with qhull's half-space
    intersection around a Chebyshev centre found by linear programming.
    """
    centre = sites.mean(axis=0)
    s, x = sites - centre, x - centre
    spread = np.ptp(s, axis=0).max()
    vols = np.zeros(len(s))
    for i in range(len(s)):
        others = np.delete(np.arange(len(s)), i)
        normals = np.vstack([2 * (s[others] - s[i]), 2 * (s[i] - x)])
        offsets = np.concatenate([-((s[others] ** 2).sum(1) - s[i] @ s[i]), [-(s[i] @ s[i] - x @ x)]])
        norm = np.linalg.norm(normals, axis=1)
        lp = linprog(
            np.r_[0, 0, 0, -1], A_ub=np.c_[normals, norm], b_ub=-offsets, bounds=[(None, None)] * 3 + [(0, None)]
        )
        if lp.status != 0 or lp.x[3] < 1e-7 * spread:
            continue  # empty or flat stolen region
        cell = HalfspaceIntersection(np.c_[normals, offsets], lp.x[:3])
        vols[i] = ConvexHull(cell.intersections).volume
    return vols / vols.sum()


def check_properties(W, sites, queries, lin_tol=1e-9):
    assert isinstance(W, sp.csr_matrix)
    assert W.shape == (len(queries), len(sites))
    dense = W.toarray()
    assert np.isfinite(dense).all()
    np.testing.assert_allclose(dense.sum(axis=1), 1.0, atol=1e-12)
    assert dense.min() >= -1e-12
    spread = np.ptp(sites, axis=0).max()
    assert np.abs(W @ sites - queries).max() <= lin_tol * spread


# -- properties ---------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_sites_partition_nonnegative_linear(seed):
    sites = random_sites(seed, n=60)
    queries = np.random.default_rng(100 + seed).random((2000, 3))
    check_properties(natural_neighbour_weights(sites, queries), sites, queries, lin_tol=1e-12)


@pytest.mark.parametrize("spacing,offset", [(1.0, 0.0), (0.1, 0.3), (7.3, 1000.0)])
def test_regular_grid_cospherical(spacing, offset):
    # Every cube of a grid is a co-spherical cell; qhull splits it into
    # tetrahedra, some of them flat (zero volume).
    sites = grid_sites(5, spacing, (offset,) * 3)
    d = Delaunay(sites)
    vol = np.abs(np.linalg.det(sites[d.simplices[:, 1:]] - sites[d.simplices[:, :1]]))
    assert (vol < 1e-12 * spacing**3).sum() > 0  # the degenerate path is exercised
    rng = np.random.default_rng(3)
    h = np.arange(0.25, 3.8, 0.25)
    on_grid_planes = np.array(np.meshgrid(h, h, h, indexing="ij")).reshape(3, -1).T  # faces, edges, centres
    special = [
        [1.5, 1.5, 1.5],  # cube centre
        [1.5, 1.5, 1.0],  # centre of a square face
        [1.5, 1.0, 1.0],  # middle of a grid edge (on a Delaunay edge)
        [1.2, 1.7, 1.0],  # on a grid plane
        [1.6, 2.2, 1.0],  # on the circle of a square: on two circumspheres
        [2.0, 2.0, 2.0 + 1e-7],  # next to a site
    ]
    queries = np.vstack([on_grid_planes, rng.random((1000, 3)) * 3.8 + 0.1, special]) * spacing + offset
    W = natural_neighbour_weights(sites, queries)
    check_properties(W, sites, queries, lin_tol=1e-12)


@pytest.mark.parametrize("jitter", [1e-13, 1e-10, 1e-7, 1e-4])
def test_jittered_grid_slivers(jitter):
    # Nearly co-spherical sites: slivers, flat and nearly flat tetrahedra, and
    # huge-radius slivers on the (nearly planar) hull.
    rng = np.random.default_rng(int(-np.log10(jitter)))
    sites = grid_sites(5) + rng.normal(size=(125, 3)) * jitter
    queries = rng.random((2000, 3)) * 3.8 + 0.1
    check_properties(natural_neighbour_weights(sites, queries, atol=0.0), sites, queries, lin_tol=1e-9)


def test_nearly_coplanar_sites_with_cage():
    rng = np.random.default_rng(4)
    pts = np.c_[rng.random((40, 2)), rng.normal(size=40) * 1e-7]
    sites = np.vstack([pts, cage_points(pts)])
    queries = np.c_[rng.random((500, 2)), rng.normal(size=500) * 1e-7]
    check_properties(natural_neighbour_weights(sites, queries), sites, queries, lin_tol=1e-12)


def test_kronecker_delta_at_sites():
    sites = random_sites(5)
    W = natural_neighbour_weights(sites, sites)
    assert (W != sp.identity(len(sites), format="csr")).nnz == 0
    # within atol: still exactly the unit row
    atol = 1e-9 * np.linalg.norm(np.ptp(sites, axis=0))
    near = sites[:30] + atol / 4
    W = natural_neighbour_weights(sites, near)
    assert (W != sp.identity(len(sites), format="csr")[:30]).nnz == 0
    # just beyond atol: Sibson coordinates are continuous, nearly the unit row
    far = sites[:30] + 1e-7
    dense = natural_neighbour_weights(sites, far).toarray()
    assert np.abs(dense[:, :30] - np.eye(30)).max() < 1e-5
    grid = grid_sites(4)
    assert (natural_neighbour_weights(grid, grid) != sp.identity(64, format="csr")).nnz == 0


# -- independent reference ----------------------------------------------------------------


def test_matches_halfspace_reference_random():
    sites = random_sites(7, n=25)
    queries = np.random.default_rng(8).random((5, 3))
    W = natural_neighbour_weights(sites, queries).toarray()
    for q, row in zip(queries, W, strict=True):
        np.testing.assert_allclose(row, reference_weights(sites, q), atol=1e-8)


def test_matches_halfspace_reference_grid():
    sites = grid_sites(4)
    queries = np.array([[1.5, 1.5, 1.0], [1.5, 1.0, 1.0], [1.6, 2.2, 1.0], [1.25, 1.7, 2.1]])
    W = natural_neighbour_weights(sites, queries).toarray()
    for q, row in zip(queries, W, strict=True):
        np.testing.assert_allclose(row, reference_weights(sites, q), atol=1e-8)


def test_matches_halfspace_reference_jittered_grid():
    rng = np.random.default_rng(9)
    sites = grid_sites(4) + rng.normal(size=(64, 3)) * 1e-8
    queries = np.array([[1.5, 1.5, 1.0], [1.5, 1.0, 1.0], [1.2, 1.4, 1.6]])
    W = natural_neighbour_weights(sites, queries).toarray()
    for q, row in zip(queries, W, strict=True):
        np.testing.assert_allclose(row, reference_weights(sites, q), atol=1e-8)


# -- continuity and locality ---------------------------------------------------------------


def test_continuity():
    sites = random_sites(10, n=50)
    rng = np.random.default_rng(11)
    a = rng.random((300, 3))
    step = rng.normal(size=(300, 3))
    b = a + 1e-7 * step / np.linalg.norm(step, axis=1, keepdims=True)
    diff = natural_neighbour_weights(sites, a) - natural_neighbour_weights(sites, b)
    assert abs(diff).max() < 1e-4
    # across grid planes and circumspheres too
    grid = grid_sites(4)
    a = np.array([[1.6, 2.2, 1.0], [1.5, 1.5, 1.0], [1.3, 1.0, 1.0]])
    for direction in np.eye(3):
        diff = natural_neighbour_weights(grid, a + 1e-7 * direction) - natural_neighbour_weights(grid, a)
        assert abs(diff).max() < 1e-4


def test_locality_natural_neighbours():
    sites = random_sites(12, n=40)
    queries = np.random.default_rng(13).random((40, 3))
    W = natural_neighbour_weights(sites, queries)
    n = len(sites)
    for q, x in enumerate(queries):
        d = Delaunay(np.vstack([sites, x]))
        indptr, indices = d.vertex_neighbor_vertices
        neighbours = set(indices[indptr[n] : indptr[n + 1]].tolist())
        support = set(W.indices[W.indptr[q] : W.indptr[q + 1]].tolist())
        assert support == neighbours


# -- cage, hull, errors -------------------------------------------------------------------------


def test_cage_points_enclose():
    rng = np.random.default_rng(14)
    pts = rng.random((50, 3)) * [10, 20, 3] + [100, -50, 7]
    cage = cage_points(pts, margin=0.25)
    assert cage.shape == (14, 3)
    lo, hi = pts.min(0), pts.max(0)
    pad = 0.25 * (hi - lo).max()
    np.testing.assert_allclose(cage.min(0), lo - pad)
    np.testing.assert_allclose(cage.max(0), hi + pad)
    sites = np.vstack([pts, cage])
    # anything a bit inside the padded box is fine
    probe = lo - 0.9 * pad + rng.random((500, 3)) * (hi - lo + 1.8 * pad)
    assert inside_hull(sites, probe).all()
    check_properties(natural_neighbour_weights(sites, probe), sites, probe, lin_tol=1e-12)
    # and the 14 cage points only also enclose the points
    assert inside_hull(cage, pts).all()
    with pytest.raises(FaceError):
        cage_points(np.ones((3, 3)))
    with pytest.raises(FaceError):
        cage_points(pts, margin=0)


def test_outside_hull_error():
    sites = random_sites(15)
    queries = np.array([[0.5, 0.5, 0.5], [5.0, 0.0, 0.0], [0.4, 0.4, 0.4], [-3.0, 0.0, 0.0]])
    with pytest.raises(FaceError) as err:
        natural_neighbour_weights(sites, queries)
    text = str(err.value)
    assert "2 of 4 queries" in text and "first is query 1" in text
    assert err.value.hint == "add bounding control points (see cage_points)"
    np.testing.assert_array_equal(inside_hull(sites, queries), [True, False, True, False])


def test_on_hull_boundary_error():
    sites = grid_sites(3)
    on_face = np.array([[0.5, 0.5, 0.0]])  # on a hull face, unbounded Voronoi cell
    with pytest.raises(FaceError, match="outside the convex hull"):
        natural_neighbour_weights(sites, on_face)
    assert not inside_hull(sites, on_face)[0]
    # a hull site itself is fine: its unit row
    W = natural_neighbour_weights(sites, sites[:1])
    assert W[0, 0] == 1.0 and W.nnz == 1


@pytest.mark.parametrize(
    "sites,match",
    [
        (np.random.default_rng(0).random((3, 3)), "at least 4 sites"),
        (np.c_[np.random.default_rng(0).random((10, 2)), np.zeros(10)], "cannot be triangulated"),
        (np.vstack([random_sites(0), random_sites(0)[[3]]]), "coincide"),
        (np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]]), "non-finite"),
        (np.zeros((5, 2)), "shape"),
    ],
)
def test_bad_sites(sites, match):
    with pytest.raises(FaceError, match=match):
        natural_neighbour_weights(sites, np.full((1, 3), 0.25))


def test_duplicate_sites_named():
    sites = random_sites(16)
    sites = np.vstack([sites, sites[5] + 1e-12])
    with pytest.raises(FaceError, match=f"5 and {len(sites) - 1}"):
        natural_neighbour_weights(sites, sites[:1])


def test_bad_queries_and_empty():
    sites = random_sites(17)
    with pytest.raises(FaceError, match="shape"):
        natural_neighbour_weights(sites, np.zeros((4, 2)))
    with pytest.raises(FaceError, match="non-finite"):
        natural_neighbour_weights(sites, np.array([[0.5, np.inf, 0.5]]))
    W = natural_neighbour_weights(sites, np.empty((0, 3)))
    assert W.shape == (0, len(sites)) and W.nnz == 0


def test_class_reuse_matches_function():
    sites = random_sites(18)
    queries = np.random.default_rng(19).random((100, 3))
    nn = NaturalNeighbours(sites)
    a = nn.weights(queries)
    assert abs(a - natural_neighbour_weights(sites, queries)).max() == 0
    assert nn.inside(queries).all()


def test_near_hull_queries_never_silently_wrong():
    # Queries 4e-8 inside a jittered, nearly planar hull: Sibson coordinates are
    # ill-determined there in floating point.  Either the weights pass every
    # check, or the self-check refuses them with the cage hint.
    rng = np.random.default_rng(11)
    sites = grid_sites(5) + rng.normal(size=(125, 3)) * 1e-7
    hull = ConvexHull(sites)
    faces = rng.integers(len(hull.simplices), size=400)
    bary = rng.dirichlet([2, 2, 2], size=400)
    queries = np.einsum("qk,qkd->qd", bary, sites[hull.simplices[faces]]) - 4e-8 * hull.equations[faces, :3]
    queries = queries[inside_hull(sites, queries)]
    try:
        W = natural_neighbour_weights(sites, queries)
    except FaceError as err:
        assert "too close to the hull" in str(err) and "cage_points" in err.hint
    else:
        check_properties(W, sites, queries, lin_tol=1e-8)
    # a little deeper, all is well
    deeper = np.einsum("qk,qkd->qd", bary, sites[hull.simplices[faces]]) - 1e-4 * hull.equations[faces, :3]
    check_properties(natural_neighbour_weights(sites, deeper), sites, deeper, lin_tol=1e-9)
