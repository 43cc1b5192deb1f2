"""How well a pose keeps the skin smooth: edge strain and folded triangles against the neutral mesh.

A deformer can meet every FAPU rule at the feature points and still tear the skin
between them (a region of influence that ends abruptly leaves a step; weights that
change too fast across an edge leave a ridge; a triangle pushed through its
neighbours folds). Two numbers catch this:

* **edge strain** of a skin edge (a, b): ``|d_a - d_b| / |x_a - x_b|``, the change of
  displacement across the edge per unit of its neutral length (0 for a rigid shift,
  1 when the edge's ends move apart by its own length). A step shows as a large
  strain on the edges along its border.
* **folds**: skin triangles whose normal turned by more than 90 degrees (those with a
  corner inside the lip or lid loops, see below, are not counted).

Two places may strain by design and are left out of the edge strain (the *contact*
edges): the **lip contact**, where the upper and lower lips touch and the mouth bag
behind them stretches when the mouth opens, and the **lid margins**, where the lids
close over the palpebral fissure and the skin rolls into the eye socket. The rule, on
the mesh's own topology: walk the skin's edge graph along the shortest paths through
the inner lip contact points (2.2 2.6 2.4 2.8 2.3 2.9 2.5 2.7) and through each lid
margin (3.1 3.7 3.3 3.11; 3.2 3.12 3.4 3.8); take those loop vertices out of the graph;
what is then cut off from the main skin (the mouth interior, each eye socket, or on a
face whose lips are one surface the strip between them) is the loop's *inside*. An edge
is a contact edge when one of its ends is inside, or when it joins two loop vertices
that do not follow each other on the loop (a chord across the slit or the fissure).

Even an ideal interpolation cannot do better than the feature points allow: a point
moved by ``d`` while another point a geodesic distance ``g`` away stays put forces some
edge on the path between them to strain by at least ``d / g``. :func:`strain_floor`
gives that bound for a pose, so a test can tell an unavoidable strain from a ridge.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import (LID_MARGIN_LOOPS, LIP_CONTACT_LOOP, cut_off, length_graph, shortest_loop,
                                  unique_edges)

DOUBLED = set(range(4, 14)) | {16, 17} | set(range(31, 43)) | set(range(51, 61))
"""FAPs tested at twice their largest used value: lips, brows and cheeks (where ridges show)."""
UNUSED_MAGNITUDE = 200.0
"""Value a skin FAP that no stream or profile uses is tested at (the FAPU tests' value)."""


@dataclass(frozen=True)
class SkinGraph:
    """The skin's edges and which of them are contact edges (see the module docstring)."""

    edges: np.ndarray  # (E, 2) global vertex indices, a < b
    contact: np.ndarray  # (E,) bool: lip contact or lid margin
    inside: np.ndarray  # global vertex indices inside the lip and lid loops
    loops: tuple[np.ndarray, ...]  # vertex loops (lips, left lid, right lid)
    triangles: np.ndarray  # (T, 3) global skin triangles

    def geodesic(self, vertices: np.ndarray) -> sp.csr_matrix:
        """Edge-length graph over the non-contact edges (global vertex indices)."""
        return length_graph(vertices, self.edges[~self.contact])


@dataclass(frozen=True)
class Quality:
    """Smoothness of one pose: worst edge strain (and where), folded skin triangles."""

    max_strain: float
    edge: tuple[int, int]  # vertex indices of the worst edge
    where: np.ndarray  # neutral midpoint of the worst edge (mm)
    near: str  # the feature point nearest that edge
    folded: int  # folded skin triangles outside the lip and lid loops

    def describe(self) -> str:
        return f"strain {self.max_strain:.3f} at edge {self.edge} near {self.near}, {self.folded} folded"


def folded_triangles(rest: np.ndarray, posed: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Bool per triangle: its normal turned by more than 90 degrees from ``rest`` to ``posed``."""
    def normals(v):
        a, b, c = (v[triangles[:, k]] for k in range(3))
        return np.cross(b - a, c - a)
    return np.einsum("ij,ij->i", normals(rest), normals(posed)) < 0


def skin_graph(mesh: HeadMesh) -> SkinGraph:
    """The skin's edges with the lip contact and lid margin edges marked (rule: module docstring)."""
    skin = np.arange(*mesh.part_ranges["skin"])
    tris = np.asarray(mesh.triangles["skin"], dtype=np.int64)
    edges = unique_edges(tris)
    n = mesh.n_vertices
    g = length_graph(mesh.vertices, edges)
    loops, inside = [], []
    contact = np.zeros(len(edges), bool)
    for labels in (LIP_CONTACT_LOOP,) + LID_MARGIN_LOOPS:
        loop = shortest_loop(mesh, labels, g)
        loops.append(loop)
        inner = cut_off(g, skin, loop)
        inside.append(inner)
        is_in = np.zeros(n, bool)
        is_in[inner] = True
        contact |= is_in[edges[:, 0]] | is_in[edges[:, 1]]
        pos = np.full(n, -1)
        pos[loop] = np.arange(len(loop))
        pa, pb = pos[edges[:, 0]], pos[edges[:, 1]]
        both = (pa >= 0) & (pb >= 0)
        step = np.abs(pa - pb)
        contact |= both & (step != 1) & (step != len(loop) - 1)
    return SkinGraph(edges=edges, contact=contact, inside=np.unique(np.concatenate(inside)),
                     loops=tuple(loops), triangles=tris)


def measure(mesh: HeadMesh, posed: np.ndarray, graph: SkinGraph | None = None) -> Quality:
    """Edge strain (contact edges left out) and folded skin triangles of ``posed`` against ``mesh``."""
    graph = graph or skin_graph(mesh)
    rest = mesh.vertices
    d = np.asarray(posed) - rest
    e = graph.edges[~graph.contact]
    strain = np.linalg.norm(d[e[:, 0]] - d[e[:, 1]], axis=1) / np.linalg.norm(rest[e[:, 0]] - rest[e[:, 1]], axis=1)
    k = int(np.argmax(strain))
    a, b = int(e[k, 0]), int(e[k, 1])
    mid = 0.5 * (rest[a] + rest[b])
    fps = mesh.feature_points()
    near = mesh.fp_labels[int(np.argmin(np.linalg.norm(fps - mid, axis=1)))]
    is_in = np.zeros(len(rest), bool)
    is_in[graph.inside] = True
    outside = ~is_in[graph.triangles].any(axis=1)
    folded = int(folded_triangles(rest, posed, graph.triangles[outside]).sum())
    return Quality(max_strain=float(strain[k]), edge=(a, b), where=mid, near=near, folded=folded)


def strain_floor(mesh: HeadMesh, posed: np.ndarray, graph: SkinGraph | None = None) -> tuple[float, str, str]:
    """The least worst edge strain any skin interpolation of this pose's feature points could have.

    max over skin feature point pairs of |d_i - d_j| / geodesic(i, j), the geodesic over the
    non-contact edges; returns (bound, label i, label j).
    """
    graph = graph or skin_graph(mesh)
    skin = mesh.part("skin")
    idx = [i for i, v in enumerate(mesh.fp_vertex) if skin.start <= v < skin.stop]
    verts = mesh.fp_vertex[idx]
    verts, first = np.unique(verts, return_index=True)
    idx = [idx[k] for k in first]
    geo = dijkstra(graph.geodesic(mesh.vertices), indices=verts)[:, verts]
    d = np.asarray(posed)[verts] - mesh.vertices[verts]
    diff = np.linalg.norm(d[:, None] - d[None], axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where((geo > 0) & np.isfinite(geo), diff / geo, 0.0)
    i, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    return float(ratio[i, j]), mesh.fp_labels[idx[i]], mesh.fp_labels[idx[j]]


@lru_cache(maxsize=1)
def used_magnitudes() -> dict[int, tuple[float, float]]:
    """FAP -> (largest positive, largest negative magnitude) the real streams and profiles use.

    Read from ``data/fap_magnitudes.csv`` (regenerate with ``tools/fap_magnitudes.py``).
    """
    with (resources.files("mpeg4fa.face") / "data" / "fap_magnitudes.csv").open(encoding="utf-8") as f:
        return {int(r["fap"]): (float(r["max_pos"]), float(r["max_neg"])) for r in csv.DictReader(f)}


def check_values(fap: int, unidirectional: bool = False) -> list[float]:
    """The values the smooth-skin check poses ``fap`` at: the largest used per sign (x2 for
    :data:`DOUBLED` FAPs); a FAP never used is posed at +-:data:`UNUSED_MAGNITUDE`."""
    pos, neg = used_magnitudes().get(fap, (0.0, 0.0))
    if pos == 0 and neg == 0:
        pos, neg = UNUSED_MAGNITUDE, (0.0 if unidirectional else UNUSED_MAGNITUDE)
    factor = 2.0 if fap in DOUBLED else 1.0
    return [s * factor * m for s, m in ((1.0, pos), (-1.0, neg)) if m > 0]
