"""Model-editing operations: small pure functions over one :class:`EditMesh` (plain numpy arrays).

Each returns a new mesh and leaves its input alone, so a session's undo is a stack of snapshots.
Vertices are never created: filling a hole fans triangles over the loop's own vertices, so every
vertex keeps ``origin`` (its index in the head it was loaded from, -1 for a foreign mesh).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from mpeg4fa.errors import MpegFaError
from mpeg4fa.face.fapu import Fapu, measure_fapu
from mpeg4fa.fdp.model import MAX_COORDINATE, first_unbounded
from mpeg4fa.spec import FEATURE_POINT_MIRROR, FEATURE_POINTS

LABELS = tuple(fp.label for fp in FEATURE_POINTS)
PART_NAME = re.compile(r"^[a-z][a-z0-9_]{0,39}$")
UNASSIGNED = "unassigned"
CLOSED_PARTS = ("eye_l", "eye_r", "tongue")
"""Parts that must be closed surfaces (watertight) on save; the skin and teeth may be open."""


class EditError(MpegFaError):
    """An edit that cannot be made (a bad index, an open loop, an unknown part or label)."""


@dataclass(frozen=True)
class EditMesh:
    vertices: np.ndarray  # (V, 3) float64
    triangles: np.ndarray  # (T, 3) int64
    tri_part: np.ndarray  # (T,) int64 index into part_names
    part_names: tuple[str, ...]
    points: dict[str, int] = field(default_factory=dict)  # feature point label -> vertex index
    origin: np.ndarray | None = None  # (V,) index in the source head, -1 where none
    source: str = ""

    def __post_init__(self) -> None:
        if self.origin is None:
            object.__setattr__(self, "origin", np.full(len(self.vertices), -1, np.int64))

    @property
    def parts(self) -> list[str]:
        """Per-triangle part names."""
        return [self.part_names[i] for i in self.tri_part]

    def same(self, other: "EditMesh") -> bool:
        return (self.part_names == other.part_names and self.points == other.points
                and all(np.array_equal(getattr(self, k), getattr(other, k))
                        for k in ("vertices", "triangles", "tri_part", "origin")))


def make_mesh(vertices, triangles, parts=None, points=None, origin=None, source="") -> EditMesh:
    """An :class:`EditMesh` from arrays; ``parts`` per triangle (names), default all ``skin``."""
    v = np.array(vertices, dtype=np.float64).reshape(-1, 3)
    t = np.array(triangles, dtype=np.int64).reshape(-1, 3)
    check_vertices(v)
    if len(t) and (t.min() < 0 or t.max() >= len(v)):
        raise EditError(f"triangle indices must lie in 0..{len(v) - 1}")
    names = list(parts) if parts is not None else ["skin"] * len(t)
    if len(names) != len(t):
        raise EditError(f"{len(names)} part names for {len(t)} triangles")
    order = tuple(dict.fromkeys(names))
    index = {n: i for i, n in enumerate(order)}
    mesh = EditMesh(v, t, np.array([index[n] for n in names], np.int64), order, {}, 
                    None if origin is None else np.asarray(origin, np.int64), source)
    for label, vertex in (points or {}).items():
        mesh = assign_point(mesh, label, int(vertex))
    return mesh


def from_head(head) -> EditMesh:
    """The editable form of a :class:`~mpeg4fa.face.mesh.HeadMesh` (the generic or any built head)."""
    names, tris = [], []
    for name, t in head.triangles.items():
        names += [name] * len(t)
        tris.append(np.asarray(t, np.int64))
    points = {label: int(v) for label, v in zip(head.fp_labels, head.fp_vertex)}
    return make_mesh(head.vertices, np.concatenate(tris), names, points, np.arange(head.n_vertices),
                     source=head.source or "head")


# ---- checks ------------------------------------------------------------------------------------

def check_vertices(vertices: np.ndarray) -> None:
    """Refuse coordinates a mesh cannot hold: not finite, or beyond :data:`MAX_COORDINATE`."""
    i = first_unbounded(vertices)
    if i is not None:
        raise EditError(f"vertex {i} would lie at ({', '.join(f'{x:.6g}' for x in vertices[i])}): coordinates must be "
                        f"finite and within +-{MAX_COORDINATE:g}", where="vertices",
                        hint="check the values (or the file's unit); nothing was changed")


def _indices(mesh: EditMesh, values, n: int, what: str) -> np.ndarray:
    idx = np.unique(np.asarray(list(values), dtype=np.int64))
    if len(idx) and (idx[0] < 0 or idx[-1] >= n):
        bad = idx[(idx < 0) | (idx >= n)][0]
        raise EditError(f"{what} {bad} does not exist", hint=f"{what}s are 0..{n - 1}")
    return idx


def _part_name(name: str) -> str:
    if not PART_NAME.match(name) or name == UNASSIGNED:
        raise EditError(f"bad part name {name!r}", hint="lower-case letters, digits and _, starting with a letter")
    return name


def _label(label: str) -> str:
    if label not in LABELS:
        raise EditError(f"{label!r} is not an MPEG-4 feature point", hint="labels are 2.1 .. 11.6 (spec/feature_points.csv)")
    return label


# ---- topology edits ----------------------------------------------------------------------------

def _keep_vertices(mesh: EditMesh, keep: np.ndarray, triangles: np.ndarray, tri_part: np.ndarray) -> EditMesh:
    """Drop the vertices not in ``keep`` (bool (V,)), renumbering triangles and points."""
    new = np.cumsum(keep) - 1
    points = {label: int(new[v]) for label, v in mesh.points.items() if keep[v]}
    return replace(mesh, vertices=mesh.vertices[keep], triangles=new[triangles], tri_part=tri_part,
                   points=points, origin=mesh.origin[keep])


def delete_faces(mesh: EditMesh, faces) -> EditMesh:
    """Remove triangles; vertices they alone used go too (vertices no face used before stay: joints)."""
    idx = _indices(mesh, faces, len(mesh.triangles), "face")
    keep_t = np.ones(len(mesh.triangles), bool)
    keep_t[idx] = False
    used_before = np.zeros(len(mesh.vertices), bool)
    used_before[mesh.triangles.ravel()] = True
    used_after = np.zeros(len(mesh.vertices), bool)
    used_after[mesh.triangles[keep_t].ravel()] = True
    keep_v = used_after | ~used_before
    return _prune_parts(_keep_vertices(mesh, keep_v, mesh.triangles[keep_t], mesh.tri_part[keep_t]))


def delete_vertices(mesh: EditMesh, vertices) -> EditMesh:
    """Remove vertices and every triangle that uses one of them."""
    idx = _indices(mesh, vertices, len(mesh.vertices), "vertex")
    keep_v = np.ones(len(mesh.vertices), bool)
    keep_v[idx] = False
    keep_t = keep_v[mesh.triangles].all(axis=1)
    return _prune_parts(_keep_vertices(mesh, keep_v, mesh.triangles[keep_t], mesh.tri_part[keep_t]))


def _prune_parts(mesh: EditMesh) -> EditMesh:
    """Drop part names no triangle has any more."""
    used = np.unique(mesh.tri_part)
    if len(used) == len(mesh.part_names):
        return mesh
    remap = np.full(len(mesh.part_names), -1, np.int64)
    remap[used] = np.arange(len(used))
    return replace(mesh, tri_part=remap[mesh.tri_part], part_names=tuple(mesh.part_names[i] for i in used))


def _half_edges(triangles: np.ndarray) -> np.ndarray:
    return np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])


def boundary_loop(mesh: EditMesh, vertices) -> list[int]:
    """Order ``vertices`` as one boundary loop, opposite to its triangles' half-edges (the new faces' winding)."""
    ring = set(int(v) for v in _indices(mesh, vertices, len(mesh.vertices), "vertex"))
    if len(ring) < 3:
        raise EditError("a hole's loop needs at least 3 vertices")
    half = _half_edges(mesh.triangles)
    undirected = np.sort(half, axis=1)
    keys, counts = np.unique(undirected, axis=0, return_counts=True)
    boundary = {tuple(k) for k, c in zip(keys.tolist(), counts) if c == 1}
    nxt: dict[int, int] = {}
    for a, b in half.tolist():  # the existing half-edge a->b: the new face runs b->a
        if (min(a, b), max(a, b)) in boundary and a in ring and b in ring:
            if b in nxt:
                raise EditError(f"vertex {b} is on more than one boundary edge of the selection",
                                hint="select the vertices of one hole only")
            nxt[b] = a
    if len(nxt) != len(ring):
        raise EditError("the selected vertices are not one closed boundary loop",
                        hint="select every vertex around one hole, and only those")
    start = min(ring)
    loop = [start]
    while nxt[loop[-1]] != start:
        loop.append(nxt[loop[-1]])
        if len(loop) > len(ring):
            break
    if len(loop) != len(ring):
        raise EditError("the selected vertices form more than one loop", hint="fill one hole at a time")
    return loop


def fill_hole(mesh: EditMesh, vertices, part: str | None = None) -> EditMesh:
    """Close the hole bounded by ``vertices`` (any order) with a fan of triangles over the loop.

    The new triangles go into ``part``, default the part of the triangles around the hole."""
    loop = boundary_loop(mesh, vertices)
    new = np.array([[loop[0], loop[i], loop[i + 1]] for i in range(1, len(loop) - 1)], np.int64)
    if part is None:
        around = np.isin(mesh.triangles, loop).any(axis=1)
        values, counts = np.unique(mesh.tri_part[around], return_counts=True)
        name = mesh.part_names[int(values[np.argmax(counts)])]
    else:
        name = _part_name(part)
    names = mesh.part_names if name in mesh.part_names else (*mesh.part_names, name)
    tri_part = np.concatenate([mesh.tri_part, np.full(len(new), names.index(name), np.int64)])
    return replace(mesh, triangles=np.concatenate([mesh.triangles, new]), tri_part=tri_part, part_names=names)


def move_vertices(mesh: EditMesh, vertices, positions=None, delta=None) -> EditMesh:
    """Set vertices to ``positions`` (one xyz each) or move them all by ``delta`` (one xyz)."""
    idx = np.asarray(list(vertices), dtype=np.int64)
    _indices(mesh, idx, len(mesh.vertices), "vertex")
    if (positions is None) == (delta is None):
        raise EditError("give either positions or delta")
    v = mesh.vertices.copy()
    if positions is not None:
        p = np.asarray(positions, np.float64)
        if p.shape != (len(idx), 3):
            raise EditError(f"{len(idx)} vertices need {len(idx)} positions [x, y, z], got shape {p.shape}")
        v[idx] = p
    else:
        d = np.asarray(delta, np.float64)
        if d.shape != (3,):
            raise EditError("delta is one [x, y, z]")
        with np.errstate(over="ignore", invalid="ignore"):
            v[np.unique(idx)] += d
    check_vertices(v)
    return replace(mesh, vertices=v)


def connected_region(mesh: EditMesh, seed_face: int, *, same_part: bool = False) -> np.ndarray:
    """The faces reachable from ``seed_face`` across shared edges (within its part with ``same_part``)."""
    (seed,) = _indices(mesh, [seed_face], len(mesh.triangles), "face")
    t = mesh.triangles
    n = len(t)
    edges = np.sort(_half_edges(t), axis=1)
    face = np.tile(np.arange(n), 3)
    order = np.lexsort((edges[:, 1], edges[:, 0]))
    e, f = edges[order], face[order]
    same = (e[1:] == e[:-1]).all(axis=1)
    a, b = f[:-1][same], f[1:][same]
    if same_part:
        ok = mesh.tri_part[a] == mesh.tri_part[b]
        a, b = a[ok], b[ok]
    graph = coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n))
    _, comp = connected_components(graph, directed=False)
    return np.flatnonzero(comp == comp[seed])


def split_part(mesh: EditMesh, faces, name: str) -> EditMesh:
    """Put the selected faces into the part ``name`` (new or existing)."""
    name = _part_name(name)
    idx = _indices(mesh, faces, len(mesh.triangles), "face")
    if not len(idx):
        raise EditError("select at least one face to split off")
    names = mesh.part_names if name in mesh.part_names else (*mesh.part_names, name)
    tri_part = mesh.tri_part.copy()
    tri_part[idx] = names.index(name)
    return _prune_parts(replace(mesh, tri_part=tri_part, part_names=names))


def rename_part(mesh: EditMesh, name: str, to: str) -> EditMesh:
    if name not in mesh.part_names:
        raise EditError(f"no part named {name!r}", hint=f"parts: {', '.join(mesh.part_names)}")
    to = _part_name(to)
    if to in mesh.part_names:
        return split_part(mesh, np.flatnonzero(mesh.tri_part == mesh.part_names.index(name)), to)
    return replace(mesh, part_names=tuple(to if n == name else n for n in mesh.part_names))


def delete_part(mesh: EditMesh, name: str) -> EditMesh:
    """Remove a part's faces (and the vertices only they used)."""
    if name not in mesh.part_names:
        raise EditError(f"no part named {name!r}", hint=f"parts: {', '.join(mesh.part_names)}")
    return delete_faces(mesh, np.flatnonzero(mesh.tri_part == mesh.part_names.index(name)))


# ---- feature points ----------------------------------------------------------------------------

def assign_point(mesh: EditMesh, label: str, vertex: int) -> EditMesh:
    (v,) = _indices(mesh, [vertex], len(mesh.vertices), "vertex")
    return replace(mesh, points={**mesh.points, _label(label): int(v)})


def clear_point(mesh: EditMesh, label: str) -> EditMesh:
    _label(label)
    return replace(mesh, points={k: v for k, v in mesh.points.items() if k != label})


def midline_x(mesh: EditMesh) -> float:
    """x of the left/right symmetry plane: the mean of the placed midline points, else 0."""
    sided = set(FEATURE_POINT_MIRROR)
    mid = [mesh.vertices[v, 0] for k, v in mesh.points.items() if k not in sided]
    return float(np.mean(mid)) if mid else 0.0


def mirror_points(mesh: EditMesh, labels=None, *, overwrite: bool = False) -> EditMesh:
    """Place each sided point's twin (``mirror`` in spec/feature_points.csv) at the vertex nearest its
    mirror image across the midline plane x = :func:`midline_x`; placed twins stay unless ``overwrite``."""
    chosen = [_label(k) for k in labels] if labels is not None else list(mesh.points)
    x0 = midline_x(mesh)
    tree = cKDTree(mesh.vertices)
    points = dict(mesh.points)
    for label in chosen:
        twin = FEATURE_POINT_MIRROR.get(label)
        if twin is None or label not in mesh.points or (twin in mesh.points and not overwrite):
            continue
        p = mesh.vertices[mesh.points[label]].copy()
        p[0] = 2 * x0 - p[0]
        points[twin] = int(tree.query(p)[1])
    return replace(mesh, points=points)


def fapu(mesh: EditMesh) -> Fapu:
    """FAPU from the placed points, by the face engine's own rule (:func:`mpeg4fa.face.fapu.measure_fapu`)."""
    return measure_fapu({k: mesh.vertices[v] for k, v in mesh.points.items()})


# ---- validation --------------------------------------------------------------------------------

def validate(mesh: EditMesh, required_points=None, *, closed_parts=CLOSED_PARTS, area_tol: float = 1e-12) -> list[str]:
    """What stops ``mesh`` being saved for the face engine (empty when nothing does).

    No degenerate triangles (repeated corner or zero area); every part named (not ``unassigned``);
    every part edge-manifold (no edge in more than two of its triangles), and the parts in
    ``closed_parts`` closed; the feature points ``required_points`` (default all 84) placed."""
    problems = []
    t, v = mesh.triangles, mesh.vertices
    if not len(t):
        return ["the mesh has no faces"]
    repeated = (t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2])
    area = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
    scale = max(float(np.ptp(v, axis=0).max()), 1e-300)
    bad = np.flatnonzero(repeated | (area <= area_tol * scale * scale))
    if len(bad):
        problems.append(f"{len(bad)} degenerate faces (first: face {bad[0]})")
    for i, name in enumerate(mesh.part_names):
        if not PART_NAME.match(name) or name == UNASSIGNED:
            problems.append(f"part {name!r} needs a name")
        edges = np.sort(_half_edges(t[mesh.tri_part == i]), axis=1)
        _, counts = np.unique(edges, axis=0, return_counts=True)
        if (counts > 2).any():
            problems.append(f"part {name} is not manifold: {(counts > 2).sum()} edges in more than two faces")
        elif name in closed_parts and (counts == 1).any():
            problems.append(f"part {name} must be closed: {(counts == 1).sum()} boundary edges")
    required = LABELS if required_points is None else [_label(k) for k in required_points]
    missing = [k for k in required if k not in mesh.points]
    if missing:
        problems.append(f"{len(missing)} feature points not placed: {', '.join(missing[:12])}"
                        + (" ..." if len(missing) > 12 else ""))
    return problems
