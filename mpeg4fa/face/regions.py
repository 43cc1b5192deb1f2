"""Regions of influence on the mesh: breadth-first search along edges (seed paper §6.2).

A feature point moves only the skin it is connected to within a few edge rings,
so the upper lip's points never drag the lower lip (close in space, far along
the surface), and the influence fades smoothly to zero at the region's border.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra


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
