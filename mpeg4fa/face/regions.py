"""Regions of influence on the mesh: which vertices a feature point may move, and how much.

Two kinds, both along the surface so that the upper lip's points never drag the
lower lip (close in space, far along the surface):

* **Skin** (:func:`detour_fade`): a feature point's weight is kept where the surface
  path to the vertex is not much longer than the straight line, and fades
  smoothly to zero where it is (across the mouth slit, from one lid to the other).
  The fade is a function of millimetres, not of edge counts, so it has no steps.
* **Tongue** (:func:`edge_hops`, :func:`falloff`): breadth-first search along edges
  with a raised-cosine falloff over a number of edge rings (seed paper §6.2).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

DETOUR_KEEP = 1.6  # surface path up to this many times the straight distance: weight kept
DETOUR_CUT = 2.6  # from this ratio on: weight 0 (the other lip, the other lid)
REACH_KEEP_MM = 22.0  # surface distance up to which a point's weight is kept whole
REACH_CUT_MM = 44.0  # ... and from which it is 0 (a left point never moves the right side)

LIP_CONTACT_LOOP = ("2.2", "2.6", "2.4", "2.8", "2.3", "2.9", "2.5", "2.7")
"""The inner lip contact, as feature points round the mouth: inside it lies the mouth bag."""
LID_MARGIN_LOOPS = (("3.1", "3.7", "3.3", "3.11"), ("3.2", "3.12", "3.4", "3.8"))
"""Each eye's lid margins (upper point, lateral corner, lower point, medial corner), left eye first: inside, the socket."""


def adjacency(triangles: np.ndarray, n_vertices: int) -> sp.csr_matrix:
    """Symmetric vertex adjacency (edges of the triangles) as a sparse 0/1 matrix."""
    t = np.asarray(triangles)
    a = np.concatenate([t[:, 0], t[:, 1], t[:, 2]])
    b = np.concatenate([t[:, 1], t[:, 2], t[:, 0]])
    m = sp.coo_matrix((np.ones(len(a)), (a, b)), shape=(n_vertices, n_vertices)).tocsr()
    m = ((m + m.T) > 0).astype(np.float64)
    return m.tocsr()


def edge_hops(graph: sp.csr_matrix, sources: np.ndarray, limit: int) -> np.ndarray:
    """``(len(sources), V)`` edge counts from each source, ``inf`` beyond ``limit`` rings."""
    if len(sources) == 0:
        return np.zeros((0, graph.shape[0]))
    return dijkstra(graph, unweighted=True, indices=np.asarray(sources), limit=limit + 0.5)


def falloff(hops: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Raised-cosine weight: 1 at the point, 0 past ``reach`` rings (per row)."""
    reach = np.asarray(reach, dtype=float)[:, None]
    with np.errstate(invalid="ignore"):
        x = np.where(np.isfinite(hops), hops / (reach + 1.0), np.inf)
    return np.where(x < 1.0, 0.5 * (1.0 + np.cos(np.pi * np.clip(x, 0.0, 1.0))), 0.0)


def unique_edges(triangles: np.ndarray) -> np.ndarray:
    """Each undirected edge of the triangles once, as (a, b) with a < b."""
    t = np.asarray(triangles, dtype=np.int64)
    e = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    return np.unique(e, axis=0)


def triangle_pairs(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``(a, b)`` of the triangles that share an edge, one row per shared edge."""
    t = np.asarray(triangles, dtype=np.int64)
    edges = np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1)
    owner = np.tile(np.arange(len(t)), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    e, o = edges[order], owner[order]
    same = np.all(e[1:] == e[:-1], axis=1)
    return o[:-1][same], o[1:][same]


def unit_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``(T, 3)`` unit normals of the triangles (0 for a degenerate one)."""
    p = vertices[triangles]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)


def length_graph(vertices: np.ndarray, edges: np.ndarray) -> sp.csr_matrix:
    """Symmetric graph of ``edges`` weighted by their lengths (mm) in ``vertices``."""
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    w = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
    n = len(vertices)
    g = sp.coo_matrix((w, (e[:, 0], e[:, 1])), shape=(n, n))
    return (g + g.T).tocsr()


def edge_graph(vertices: np.ndarray, triangles: np.ndarray) -> sp.csr_matrix:
    """Symmetric graph of the triangles' edges weighted by their lengths (mm)."""
    return length_graph(vertices, unique_edges(triangles))


def path_through(graph: sp.csr_matrix, stops: list[int], *, closed: bool = False) -> np.ndarray:
    """Vertices of the chain of shortest paths through ``stops`` in order (back to the first when
    ``closed``; a closed loop does not repeat its start)."""
    legs = list(zip(stops, stops[1:] + stops[:1])) if closed else list(zip(stops, stops[1:]))
    out: list[int] = [] if closed else [int(stops[0])]
    for a, b in legs:
        _, pred = dijkstra(graph, indices=a, return_predecessors=True)
        path = [int(b)]
        while path[-1] != a:
            if pred[path[-1]] < 0:
                raise ValueError(f"no path along the surface from vertex {a} to {b}")
            path.append(int(pred[path[-1]]))
        out.extend(path[::-1][:-1] if closed else path[::-1][1:])
    return np.array(out)


def shortest_loop(mesh, labels: tuple[str, ...], graph: sp.csr_matrix | None = None) -> np.ndarray:
    """Skin vertices of the closed loop of shortest paths through the feature points ``labels``."""
    graph = edge_graph(mesh.vertices, mesh.triangles["skin"]) if graph is None else graph
    return path_through(graph, [int(mesh.fp_vertex[mesh.fp_index(label)]) for label in labels], closed=True)


def cut_off(graph: sp.csr_matrix, vertices: np.ndarray, loop: np.ndarray) -> np.ndarray:
    """Which of ``vertices`` the ``loop`` separates from the largest part of them (the inside)."""
    keep = np.zeros(graph.shape[0], bool)
    keep[vertices] = True
    keep[loop] = False
    mask = sp.diags(keep.astype(float))
    _, comp = connected_components(mask @ graph @ mask, directed=False)
    sizes = np.bincount(comp[keep], minlength=comp.max() + 1)
    return np.flatnonzero(keep & (comp != int(np.argmax(sizes))))


def smooth_down(x: np.ndarray) -> np.ndarray:
    """1 for x <= 0, 0 for x >= 1, a cubic with zero slope at both ends in between."""
    t = np.clip(x, 0.0, 1.0)
    return 1.0 - t * t * (3.0 - 2.0 * t)


def detour_fade(vertices: np.ndarray, triangles: np.ndarray,
                sources: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two ``(len(sources), V)`` fades in 0..1: (the surface is the short way, the vertex is near).

    The ratio of surface distance (shortest edge path) to straight distance is about
    1 on the skin around a point and grows past 3 across a slit; the fade takes it
    from 1 at :data:`DETOUR_KEEP` to 0 at :data:`DETOUR_CUT`, smoothly. The
    second fade goes from 1 to 0 between :data:`REACH_KEEP_MM` and :data:`REACH_CUT_MM` of
    surface distance, so that weights stay local (a left point leaves the right side alone).
    """
    sources = np.asarray(sources)
    if len(sources) == 0:
        return np.zeros((0, len(vertices))), np.zeros((0, len(vertices)))
    geo = dijkstra(edge_graph(vertices, triangles), indices=sources, limit=max(REACH_CUT_MM, 1.0) * DETOUR_CUT)
    straight = np.linalg.norm(vertices[None, :, :] - vertices[sources][:, None, :], axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(straight > 0, geo / np.where(straight > 0, straight, 1.0), 1.0)
    near = smooth_down((geo - REACH_KEEP_MM) / (REACH_CUT_MM - REACH_KEEP_MM))
    return smooth_down((ratio - DETOUR_KEEP) / (DETOUR_CUT - DETOUR_KEEP)), near


def soft_floor(w: np.ndarray, floor: float) -> np.ndarray:
    """``max(w - floor, 0) / (1 - floor)``: tiny weights go to 0 without a step (1 stays 1, 0 stays 0)."""
    return np.maximum(w - floor, 0.0) / (1.0 - floor)


WIDE_REACH_MM = 50.0
"""A wide weight is 0 from this surface distance of its point on (the narrow ones fade out by 44 mm)."""
WIDE_MEMBRANE = 0.03
"""Membrane stiffness of the wide weights per unit of bending (1/mm^2): smooth near the point (bending),
nearly linear beyond ~6 mm (membrane), so the slope spreads evenly between a point and what holds it.
Bending alone (0) left 2 fold lines at the outer eye corner under brows at 400; 0.1 made each point a
peak (brows raised together came out wavy)."""


def wide_weights(vertices: np.ndarray, triangles: np.ndarray, points: np.ndarray,
                 held: list[np.ndarray], reach: np.ndarray | None = None) -> np.ndarray:
    """``(V, len(points))`` weights over the widest support the held skin leaves: 1 at each point,
    0 at its ``held`` vertices (the other points, the lid margins) and past its ``reach`` (mm of surface
    distance, :data:`WIDE_REACH_MM` unless given per point).

    Each minimises ``w (L M^-1 L + WIDE_MEMBRANE L) w`` (L the cotangent Laplacian, M the vertex
    areas): the smoothest fall-off from the point to what holds it, so that a displacement larger
    than the narrow weights' reach is spread over all the skin that may follow (the forehead up to
    the hairline under a 20 mm brow raise) instead of turning a band of it over.
    """
    from scipy.sparse.linalg import splu

    from mpeg4fa.face.elastic import cotan_laplacian

    n = len(vertices)
    lap, mass = cotan_laplacian(vertices, triangles, n)
    mass = np.maximum(mass, 1e-9 * max(float(mass.mean()), 1e-12))
    energy = (lap.T @ sp.diags(1.0 / mass) @ lap + WIDE_MEMBRANE * lap).tocsr()
    reach = np.full(len(points), WIDE_REACH_MM) if reach is None else np.asarray(reach, float)
    geo = dijkstra(edge_graph(vertices, triangles), indices=np.asarray(points), limit=float(reach.max()) + 1.0)
    out = np.zeros((n, len(points)))
    for k, point in enumerate(points):
        fixed = ~(geo[k] < reach[k])
        fixed[held[k]] = True
        fixed[point] = True
        free = np.flatnonzero(~fixed)
        out[point, k] = 1.0
        if len(free):
            rhs = -energy[free][:, [point]].toarray().ravel()
            out[free, k] = splu(energy[free][:, free].tocsc()).solve(rhs)
    return np.clip(out, 0.0, 1.0)
