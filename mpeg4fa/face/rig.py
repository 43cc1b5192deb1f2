"""Layer 3 set-up: how feature point motion spreads to the mesh, computed once per face.

* **Skin**: every skin vertex gets Sibson (natural-neighbour) coordinates with
  respect to the skin feature points plus a zero-motion cage (so weights exist
  everywhere and far skin stays put). Sibson coordinates already vanish smoothly
  at the edge of a point's natural-neighbour region, so they are not cut to an
  edge-ring region (that cut left a step where the weight was still large, e.g. a
  raised block of forehead); they are only faded where the surface path is much
  longer than the straight line (:func:`.regions.detour_fade`: the other lip, the
  other lid) and renormalised, so that a point seen only the long way round takes
  no share (the upper lip neither drags nor holds the lower lip); weights under
  :data:`WEIGHT_FLOOR` are soft-thresholded away and every weight fades out between
  22 and 44 mm of surface distance from its point; the weights of points other
  than the eye's (3.x) fade to 0 over :data:`LID_CLEAR_MM` (or the point's own distance
  to the margin, if less) before a lid margin (a brow raise must not pull the margin off
  the eyeball; a fade that short left a brow raise's whole stretch in one band over the lid)
  (no step, fewer rows to move). A feature point's own vertex has weight 1 for
  itself and 0 for every other point, so each point moves exactly as its FAPs say
  and no other feature point moves.
* **Tongue**: Sibson weights on the tongue's own points 6.1-6.4 plus fixed root
  points, cut to edge-ring regions with a raised-cosine falloff.
* **Jaw**: a weight per vertex read off the CC0 ``jawOpen`` face unit (the fraction
  of a rigid jaw rotation each vertex follows), 1 on the lower teeth and at 2.1.
* **Head**: 1 on the whole head, fading to 0 down the neck: a neck vertex turns by a share
  of the head's rotation that grows from 0 at the cut to 1 where the neck meets the head (the
  jaw line at the front, so the skin under the chin takes part; the skull's base at the back:
  :func:`head_weights`), evenly in the angle seen from 7.1, so a turn twists the neck along its
  length instead of folding it in one band, and a nod spreads over the whole throat.
* **Lids**: sheets of skin turning about the eye centres (:mod:`.lids`).
* **Eyes, upper teeth**: rigid.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

from mpeg4fa.face import motion, sibson
from mpeg4fa.face.couplings import PASSIVE_POINTS, add_couplings, couplings
from mpeg4fa.face.fapu import Fapu
from mpeg4fa.face.kept import kept_sparse
from mpeg4fa.face.lids import LidSheet, build_lids
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import (LID_MARGIN_LOOPS, adjacency, detour_fade, edge_graph, edge_hops, falloff,
                                  shortest_loop, smooth_down, soft_floor)
from mpeg4fa.face.sibson import cage_points, natural_neighbour_weights
from mpeg4fa.spec import FAPS, N_FAPS

JAW_WEIGHT_FLOOR = 0.03  # jaw weights below this are noise of the face unit: dropped
CORNER_HOLD_MM = 10.0
"""Round each outer lip corner the lips share the corner's jaw weight, their difference from it growing
smoothly to the face unit's own over this surface distance: the face unit's upper and lower lips
differed by 0.03-0.1 across the corner's 0.3 mm edges, the worst strain of an open jaw (1.57, 2.6 x
its floor at FAP 3 = 900; 2.3 x with a -40 degree nod, 2.46 x on ARKit). 3 mm left 2.0-2.5 x; 5-8 mm
keep the feature-point deformer within 2 x but ARKit's blend to its sculpt, further out, folded the
lower lip under yaw 40 pitch 20; 10 mm (ARKit refitting as far): the jaw alone 1.56 x / 1.67 x,
every nod and turn with the jaw open 1.27-1.77 x, no fold (tools/crease_check.py)."""
NECK_TOP = ((0.55, 0.30), (-0.25, 0.70))
"""Where the neck meets the head, front then back, as (depth, height): depth in units of the
7.1 -> 2.1 depth ahead of 7.1 (0.55: just behind the chin's underside; -0.25: behind the spine),
height as the share of the height from the neck's cut up to 7.1 (0.30: under the chin; 0.70:
the skull's base). The head's rotation fades in over the neck below the line through them
(and below the jaw line, :data:`JAW_LINE_MARGIN_MM`, where that is higher)."""
THROAT_BOW_DEGREES = 20.0
"""The deepest bow (head pitch down, FAP 48 > 0) the throat takes alone; past it the whole neck, its cut
included, turns by the excess about 7.1 and shares out the rest as before (``feature_points.neck_bow``).
With the cut held, a bow about 7.1 drives the chin into the neck's column (at 40 degrees it lands 18 mm
below the cut): with the widest viseme's jaw the throat drew fold lines from 22 degrees and folded from
32 (36 triangles at 40). Looking up, turning and tilting stretch the throat instead and pass at 40
degrees; the real streams bow at most 15.8 degrees."""
JAW_LINE_MARGIN_MM = 6.0
"""At the front the head's share reaches 1 this far below the jaw line (the plane through the chin
2.1 and the jaw angles 2.13/2.14), so the skin under the chin blends between the head and the neck:
with the line at the old height under the chin (36 mm above the cut) a nod of 20-40 degrees put the
whole turn into the throat's two rows of 15 mm edges (strain 2.7 x the floor looking up, folds
looking down); 5-7 mm measure the same, 2 mm or less runs the line through the jaw's lower edge,
whose small triangles then fold."""
JAW_LINE_FALL = 1.0
"""Behind the jaw angles the line falls this many mm per mm back, down to the line :data:`NECK_TOP` draws
(the ear and the nape keep the share they had)."""
SHARE_POWER = 1.5
"""The share is ``1 - (1 - t)**SHARE_POWER`` of the angle ``t`` (0 at the cut, 1 at the line): level
where it meets the head (no crease along the line), nowhere more than 1.5 x as steep as an even rise. Folds
come where a nod turns one row past the next: a share that rises evenly in the angle from 7.1 keeps
each row behind the one above it up to a nod as large as the angle the throat spans (33 degrees from
the cut to the chin)."""
TONGUE_ROOT_MM = 6.0  # tongue vertices within this of its back end are fixed
TONGUE_REACH_MM = 30.0  # a tongue point carries the tongue around it this far (its tip the front third)
WEIGHT_FLOOR = 0.01  # skin weights are soft-thresholded by this (a 1 % weight moves 0.2 mm at 20 mm)
LID_CLEAR_MM = 24.0  # brow, cheek and nose weights fade to 0 over this surface distance before a lid margin
# (or over the point's own distance to it, if less)
# (6 mm left the whole stretch of a brow raise in a band just over the lid: brows at 400 folded there)
RELIEVED = {41: (100.0, 200.0), 42: (100.0, 200.0)}
"""FAP -> values at which the skin weights of its point are evened out where the FAP alone folds the skin
(:func:`.fold_relief.even_out`, every feature point held): the cheek lifts of joy at 63 (200 ENS, 10 mm on the
generic head) drew a fold line 3-9 mm above each cheek point 5.3/5.4, where the weight falls from 0.73 to 0.31
across a ridge already creased 40 degrees at rest; evened out (8 vertices, by at most 0.12 of weight) none.
Evened out up to joy at 63 x 2 (400) the weights spread to the lid margins and the strain rose to 15 x its
floor at 200, while 400 folds anyway (5.3 rises past the outer eye corner 3.7 that no FAP moves)."""
JAW_RELIEVED = (1568.0, 1800.0)
"""open_jaw values (MNS) at which the jaw shares are evened out where the jaw alone folds the skin
(:func:`_relieve_jaw`). The jawOpen face unit leaves stray shares of 0.031-0.032 (just over
:data:`JAW_WEIGHT_FLOOR`) on single vertices round the nostrils, whose 1 mm triangles turned into 8 fold lines
from 1383 (26 degrees of jaw at 1568, the tracker's streams; 1568 alone evened out left folds under the chin
from 1592); evened out at 1568 and 1800 (188 vertices, by at most 0.22, the most under the chin and inside the
mouth's floor) the jaw alone passes up to 1848 (33.5 degrees at 1800), its strain 1.56 x the floor as before.
Evened out to 1900 or 2000 (46 degrees, the jaw's end) the shares moved up to 0.47 and folded the lips."""
CORNERS = (("2.4", "8.3"), ("2.5", "8.4"))  # (inner, outer) lip corner, left then right
CORNER_MARGIN_MM = 1.0  # the outer lip corner stays at least this far outside the inner one


@dataclass(frozen=True)
class Rig:
    """Everything a frame needs, precomputed for one neutral face."""

    rest: np.ndarray  # (V, 3)
    fapu: Fapu
    translate: np.ndarray  # (84*3, 68): FAP values -> feature point displacement
    weights: sp.csr_matrix  # (V, 84): feature point displacement -> vertex displacement
    moving: np.ndarray  # vertex indices with any feature point weight
    weights_moving: sp.csr_matrix  # weights restricted to the moving rows
    lid_fp: dict[int, int]  # lid FAP -> feature point index
    lids: dict[int, LidSheet]  # lid FAP -> the lid sheet it turns (see :mod:`.lids`)
    jaw_rows: tuple[np.ndarray, np.ndarray]
    head_fade: tuple[np.ndarray, np.ndarray]  # neck vertices that turn only partly with the head, and their share
    roll_rows: dict[int, tuple[np.ndarray, np.ndarray, float]]  # fp index -> (vertices, weights, side)
    parts: dict[str, slice]
    joints: dict[str, int]
    fp_vertex: np.ndarray
    chin_fp: int  # 2.1, the point FAP 3 drops
    head_fp: int  # 7.1, the head's rotation centre
    corners: tuple[tuple[int, int], ...] = ()  # (inner, outer) lip corner feature points, left then right


def build_rig(mesh: HeadMesh, fapu: Fapu) -> Rig:
    """Precompute the weights of ``mesh`` (its current vertices are the neutral face)."""
    rest = mesh.vertices
    labels = mesh.fp_labels
    fp_vertex = mesh.fp_vertex
    index = {label: i for i, label in enumerate(labels)}

    translate = np.zeros((len(labels) * 3, N_FAPS))
    lid_fp: dict[int, int] = {}
    for record in FAPS[2:]:
        k = motion.kind(record.number)
        if k == "translate":
            for label in record.feature_point:
                i = index[label]
                translate[3 * i:3 * i + 3, record.number - 1] = fapu.unit(record.fapu) * motion.direction(record.number)
        elif k == "lid":
            lid_fp[record.number] = index[record.feature_point[0]]
    add_couplings(translate, index, fapu)  # documented extra points (lip protrusion, lid skin)

    driven = sorted({index[label] for r in FAPS[2:] if motion.kind(r.number) in ("translate", "lid", "tongue_roll")
                     for label in r.feature_point} | {index[label] for _, label, _ in couplings() if label in index})
    skin = mesh.part("skin")
    tongue = mesh.part("tongue")
    columns = []
    anchors = [i for i in range(len(labels)) if _in(fp_vertex[i], skin) and labels[i] not in PASSIVE_POINTS]
    columns.append(skin_weights(mesh, anchors, driven))
    tongue_fps = [i for i in range(len(labels)) if _in(fp_vertex[i], tongue)]
    if tongue_fps:  # a head without a tongue (or without its points) has no tongue weights
        columns.append(_mirror_symmetric(mesh, tongue, part_weights(
            mesh, tongue, tongue_fps, driven, extra_controls=_tongue_root(rest, tongue), reach=_tongue_reach(mesh, tongue))))
    else:
        columns.append(sp.csr_matrix((mesh.n_vertices, len(labels))))
    weights = relieve(mesh, (columns[0] + columns[1]).tocsr(), translate, index)
    weights.eliminate_zeros()
    moving = np.unique(weights.nonzero()[0])

    roll_rows = {}
    for label, side in (("6.3", 1.0), ("6.4", -1.0)):
        col = weights[:, index[label]].tocoo()
        roll_rows[index[label]] = (col.row, col.data, side)
    # lid points and tongue borders move by rotation, not by the translation table
    for i in list(lid_fp.values()):
        translate[3 * i:3 * i + 3] = 0.0

    return Rig(
        rest=rest, fapu=fapu, translate=translate, weights=weights, moving=moving,
        weights_moving=weights[moving], lid_fp=lid_fp, lids=build_lids(mesh),
        jaw_rows=_jaw_weights(mesh, fapu), head_fade=head_weights(mesh), roll_rows=roll_rows,
        parts={p: mesh.part(p) for p in mesh.part_ranges}, joints=dict(mesh.joints), fp_vertex=fp_vertex,
        chin_fp=index["2.1"], head_fp=index["7.1"],
        corners=tuple((index[a], index[b]) for a, b in CORNERS if a in index and b in index),
    )


def relieve(mesh: HeadMesh, weights: sp.csr_matrix, translate: np.ndarray, index: dict[str, int]) -> sp.csr_matrix:
    """``weights`` with the columns of the :data:`RELIEVED` FAPs' points evened out where the FAP alone folds
    the skin."""
    from mpeg4fa.face.fold_relief import even_out, skin_triangles
    todo = [(fap, index[FAPS[fap - 1].feature_point[0]]) for fap in RELIEVED
            if FAPS[fap - 1].feature_point[0] in index]
    if not todo:
        return weights
    rest, tris, held = mesh.vertices, skin_triangles(mesh), [np.asarray(mesh.fp_vertex, dtype=np.int64)]
    out = weights.tolil()
    for fap, j in todo:
        step = translate[3 * j:3 * j + 3, fap - 1]  # mm per unit of the FAP at its point
        column = weights[:, j].toarray().ravel()
        column = even_out(rest, tris, [column], lambda f: (rest + np.outer(f[0], value * step)
                                                           for value in RELIEVED[fap]), held)[0]
        out[:, j] = column[:, None]
    return out.tocsr()


def _in(v: int, s: slice) -> bool:
    return s.start <= v < s.stop


def _sibson(mesh: HeadMesh, part: slice, fps: list[int],
            extra_controls: np.ndarray | None) -> tuple[list[int], sp.csc_matrix]:
    """One control per distinct vertex (11.5 shares 11.4's) and the part's Sibson weights on them."""
    rest = mesh.vertices
    fp_v = mesh.fp_vertex
    controls, seen = [], set()
    for i in fps:
        if fp_v[i] not in seen:
            seen.add(fp_v[i])
            controls.append(i)
    sites = [rest[fp_v[controls]]]
    if extra_controls is not None:
        sites.append(extra_controls)
    queries = rest[part]
    cloud = np.concatenate(sites + [queries])
    sites.append(cage_points(cloud))
    sites = np.concatenate(sites)
    # kept in the user cache: the Delaunay insertions are half a second of every start that poses a head
    w = kept_sparse("sibson", (sites, queries), (sibson,), lambda: natural_neighbour_weights(sites, queries))
    return controls, w[:, :len(controls)].tocsc()


def _driven_controls(mesh: HeadMesh, part: slice, fps: list[int], driven: list[int],
                     extra_controls: np.ndarray | None):
    """Sibson set-up of a part: its controls, their weights, and which of them FAPs drive."""
    controls, w = _sibson(mesh, part, fps, extra_controls)
    return controls, w, [c for c, i in enumerate(controls) if i in driven]


def skin_weights(mesh: HeadMesh, fps: list[int], driven: list[int]) -> sp.csr_matrix:
    """``(V, 84)`` skin weights of the ``driven`` points among the skin feature points ``fps``.

    Sibson coordinates (smooth, exact at the points), faded where the surface goes the
    long way round (:func:`.regions.detour_fade`), soft-thresholded by :data:`WEIGHT_FLOOR`.
    """
    skin = mesh.part("skin")
    n, fp_v = mesh.n_vertices, mesh.fp_vertex
    controls, w, keep = _driven_controls(mesh, skin, fps, driven, None)
    if not keep:
        return sp.csr_matrix((n, len(mesh.fp_labels)))
    local = mesh.vertices[skin]
    fade, near = detour_fade(local, mesh.triangles["skin"] - skin.start, fp_v[controls] - skin.start)
    dense = w.toarray().T  # (controls, V)
    # a point seen only the long way round (2.2 from the lower lip) takes no share: the others fill it
    # (Sibson weights sum to 1 over points and cage; the cage is never faded)
    share = 1.0 - (dense * (1.0 - fade)).sum(axis=0)
    faded = dense * fade / np.maximum(share, 1e-12) * near  # then local: 0 past REACH_CUT_MM
    # the lid margins belong to the lids (and the eye points): other points leave them in place
    margins = np.concatenate([shortest_loop(mesh, labels) for labels in LID_MARGIN_LOOPS]) - skin.start
    to_margin = dijkstra(edge_graph(local, mesh.triangles["skin"] - skin.start), indices=margins,
                         min_only=True, limit=LID_CLEAR_MM)
    # a point nearer a margin than LID_CLEAR_MM (the cheek's 5.3) fades over its own distance, so
    # that it still moves exactly as its FAPs say
    reach = np.minimum(LID_CLEAR_MM, to_margin[fp_v[controls] - skin.start])
    rows, cols, vals = [], [], []
    for c in keep:
        if mesh.fp_labels[controls[c]].startswith("3.") or reach[c] <= 0:
            col = faded[c]
        else:
            col = faded[c] * (1.0 - smooth_down(to_margin / reach[c]))
        col = soft_floor(col, WEIGHT_FLOOR)
        nz = np.flatnonzero(col > 0)
        rows.append(nz + skin.start)
        cols.append(np.full(len(nz), controls[c]))
        vals.append(col[nz])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, len(mesh.fp_labels)))


def part_weights(mesh: HeadMesh, part: slice, fps: list[int], driven: list[int],
                 extra_controls: np.ndarray | None, reach: np.ndarray | None = None) -> sp.csr_matrix:
    """Sibson weights of a part's vertices on its feature points, cut to their BFS regions (the tongue)."""
    n, fp_v = mesh.n_vertices, mesh.fp_vertex
    controls, w, keep = _driven_controls(mesh, part, fps, driven, extra_controls)
    if not keep:
        return sp.csr_matrix((n, len(mesh.fp_labels)))
    rings = mesh.fp_reach if reach is None else reach
    reach = np.array([max(int(rings[controls[c]]), 1) for c in keep])
    local_tris = mesh.triangles[_part_name(mesh, part)] - part.start
    graph = adjacency(local_tris, part.stop - part.start)
    hops = edge_hops(graph, fp_v[[controls[c] for c in keep]] - part.start, int(reach.max()))
    fade = falloff(hops, reach)  # (k, part vertices)
    rows, cols, vals = [], [], []
    for j, c in enumerate(keep):
        col = w[:, c].toarray().ravel() * fade[j]
        nz = np.flatnonzero(col > 1e-9)
        rows.append(nz + part.start)
        cols.append(np.full(len(nz), controls[c]))
        vals.append(col[nz])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(n, len(mesh.fp_labels)))


def _part_name(mesh: HeadMesh, part: slice) -> str:
    return next(p for p, (a, b) in mesh.part_ranges.items() if a == part.start and b == part.stop)


def _mirror_symmetric(mesh: HeadMesh, part: slice, weights: sp.csr_matrix) -> sp.csr_matrix:
    """A part's weights averaged with their mirror image (edge rings counted on a triangulation that
    is not quite mirror symmetric give each side its own weights; the tongue's are rings wide)."""
    rows = np.arange(part.start, part.stop)
    mirror = np.asarray(mesh.mirror)
    if not np.all((mirror[rows] >= part.start) & (mirror[rows] < part.stop)):
        return weights  # a part without its own mirror image: as it is
    column_at = {}
    for j, v in enumerate(mesh.fp_vertex):
        column_at.setdefault(int(v), j)
    mirror_col = np.array([column_at.get(int(mirror[v]), j) for j, v in enumerate(mesh.fp_vertex)])
    dense = weights[rows].toarray()
    both = 0.5 * (dense + weights[mirror[rows]].toarray()[:, mirror_col])
    out = sp.lil_matrix(weights.shape)
    out[rows] = both
    return out.tocsr()


def _tongue_reach(mesh: HeadMesh, tongue: slice) -> np.ndarray:
    """Edge rings per feature point that span :data:`TONGUE_REACH_MM` of the tongue (a tip moved
    alone, one ring wide, stuck out of the mouth as a spike between the teeth)."""
    tris = mesh.triangles["tongue"]
    edges = np.linalg.norm(mesh.vertices[tris[:, [1, 2, 0]]] - mesh.vertices[tris], axis=2)
    rings = max(int(np.ceil(TONGUE_REACH_MM / max(float(np.median(edges)), 1e-9))), 1)
    return np.maximum(np.asarray(mesh.fp_reach), rings)


def _tongue_root(rest: np.ndarray, tongue: slice) -> np.ndarray:
    """Fixed controls at the back of the tongue, so that tip motion does not drag its root."""
    v = rest[tongue]
    back = v[v[:, 2] < v[:, 2].min() + TONGUE_ROOT_MM]
    lo, hi = back.min(axis=0), back.max(axis=0)
    mid = (lo + hi) / 2
    return np.array([[lo[0], mid[1], mid[2]], [hi[0], mid[1], mid[2]], [mid[0], lo[1], mid[2]],
                     [mid[0], hi[1], mid[2]]])


def _jaw_weights(mesh: HeadMesh, fapu: Fapu | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fraction of the jaw rotation each vertex follows, from the jawOpen face unit, evened out where the jaw
    alone folds the skin (:func:`_relieve_jaw`, given the face's units)."""
    rest = mesh.vertices
    pivot = mesh.joint("mouth")
    chin = mesh.fp("2.1")
    if mesh.face_units is not None and "jawOpen" in mesh.face_units.names:
        delta = mesh.face_units.dense("jawOpen", mesh.n_vertices)
        d_chin = delta[mesh.fp_vertex[mesh.fp_index("2.1")]]
        a = (chin - pivot)[1:]
        b = a + d_chin[1:]
        angle = np.arctan2(b[1], b[0]) - np.arctan2(a[1], a[0])
        step = (motion.rotation_matrix(0, angle) - np.eye(3))
        r = (rest - pivot) @ step.T
        with np.errstate(invalid="ignore", divide="ignore"):
            w = np.einsum("ij,ij->i", delta, r) / np.einsum("ij,ij->i", r, r)
        w = np.nan_to_num(w)
    elif len(mesh.info.get("jaw_weights", ())) == mesh.n_vertices:  # a rigged custom mesh (:mod:`.custom`): its own jaw weights
        w = np.asarray(mesh.info["jaw_weights"], dtype=np.float64).copy()
    else:  # a face without face units (a test head): everything below the lip line
        w = (rest[:, 1] < (mesh.fp("2.2")[1] + mesh.fp("2.3")[1]) / 2).astype(float)
    w = _hold_corners(mesh, w)
    w = 0.5 * (w + w[mesh.mirror])  # the face unit is slightly asymmetric; the jaw is not
    w = np.clip(w, 0.0, 1.0)
    w[w < JAW_WEIGHT_FLOOR] = 0.0
    for part in ("eye_l", "eye_r", "teeth_upper", "joints"):
        w[mesh.part(part)] = 0.0
    w[mesh.part("teeth_lower")] = 1.0
    w[mesh.fp_vertex[mesh.fp_index("2.1")]] = 1.0
    if fapu is not None:
        w = _relieve_jaw(mesh, fapu, w)
    idx = np.flatnonzero(w)
    return idx, w[idx]


def _relieve_jaw(mesh: HeadMesh, fapu: Fapu, w: np.ndarray) -> np.ndarray:
    """``w`` evened out (:func:`.fold_relief.even_out`, every feature point held) where the jaw opened alone to a
    :data:`JAW_RELIEVED` value folds the skin, as the deformer turns it (each vertex blended toward its rotated
    position by its share), on the skin triangles further than :data:`CORNER_HOLD_MM` from the outer lip corners
    (their shares are the corner hold's, :func:`_hold_corners`)."""
    from mpeg4fa.face.fold_relief import even_out, skin_triangles
    if not JAW_RELIEVED or not all(label in mesh.fp_labels for label in ("8.3", "8.4")):
        return w
    rest, skin = mesh.vertices, mesh.part("skin")
    pivot, chin = mesh.joint("mouth"), mesh.fp("2.1")
    steps = [(rest - pivot) @ (motion.rotation_matrix(0, motion.arc_angle((chin - pivot)[1:], value * fapu.unit("MNS")))
                               - np.eye(3)).T for value in JAW_RELIEVED]
    graph = edge_graph(rest[skin], mesh.triangles["skin"] - skin.start)
    corners = [mesh.fp_vertex[mesh.fp_index(label)] - skin.start for label in ("8.3", "8.4")]
    to_corner = np.full(mesh.n_vertices, np.inf)
    to_corner[skin] = dijkstra(graph, indices=corners, min_only=True, limit=CORNER_HOLD_MM + 1.0)
    tris = skin_triangles(mesh)
    tris = tris[to_corner[tris].min(axis=1) > CORNER_HOLD_MM]
    held = np.asarray(mesh.fp_vertex, dtype=np.int64)
    return even_out(rest, tris, [w], lambda f: (rest + f[0][:, None] * step for step in steps), [held])[0]


def _hold_corners(mesh: HeadMesh, w: np.ndarray) -> np.ndarray:
    """``w`` with the skin round each outer lip corner (8.3/8.4) drawn toward the corner's own share:
    the difference from it scaled by a smooth step of the surface distance, 0 at the corner and 1 from
    :data:`CORNER_HOLD_MM` on (see there)."""
    if not all(label in mesh.fp_labels for label in ("8.3", "8.4")):
        return w
    skin = mesh.part("skin")
    graph = edge_graph(mesh.vertices[skin], mesh.triangles["skin"] - skin.start)
    out = w.copy()
    for label in ("8.3", "8.4"):
        corner = mesh.fp_vertex[mesh.fp_index(label)]
        r = dijkstra(graph, indices=corner - skin.start, limit=CORNER_HOLD_MM + 1.0)
        out[skin] = w[corner] + (out[skin] - w[corner]) * (1.0 - smooth_down(r / CORNER_HOLD_MM))
    return out


def head_weights(mesh: HeadMesh) -> tuple[np.ndarray, np.ndarray]:
    """The vertices that turn only partly with the head, and their share of its rotation.

    A neck vertex's share grows from 0 at the cut to 1 at the line where the neck meets the head:
    :data:`NECK_TOP` at the sides and back, the jaw line less :data:`JAW_LINE_MARGIN_MM` at the front,
    whichever is higher. It grows with the angle between straight down from 7.1 and the vertex
    (a cone about the vertical through 7.1): a nod turns every point about 7.1, so a share even in
    that angle spreads the nod evenly along the throat. Everything not listed turns fully."""
    v = mesh.vertices
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    skin = mesh.part("skin")
    bottom = y[skin].min()
    centre, chin = mesh.fp("7.1"), mesh.fp("2.1")
    depth, height = chin[2] - centre[2], centre[1] - bottom
    (zf, hf), (zb, hb) = ((centre[2] + a * depth, bottom + b * height) for a, b in NECK_TOP)
    top = hf + (hb - hf) * np.clip((zf - z) / (zf - zb), 0.0, 1.0)
    angles = [label for label in ("2.13", "2.14") if label in mesh.fp_labels]
    if angles:
        angle = np.mean([mesh.fp(label) for label in angles], axis=0)
        slope = (angle[1] - chin[1]) / (angle[2] - chin[2]) if abs(angle[2] - chin[2]) > 1e-6 else 0.0
        jaw = chin[1] + slope * (z - chin[2]) - JAW_LINE_MARGIN_MM - JAW_LINE_FALL * np.maximum(angle[2] - z, 0.0)
        top = np.maximum(top, jaw)
    rho = np.hypot(x - centre[0], z - centre[2])
    below = np.arctan2(rho, centre[1] - y)
    at_cut = np.arctan2(rho, centre[1] - bottom)
    at_top = np.arctan2(rho, np.maximum(centre[1] - top, 1e-6))
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(np.nan_to_num((below - at_cut) / (at_top - at_cut), nan=1.0), 0.0, 1.0)
    t[y >= top] = 1.0
    t[_cut_off_from_the_cut(mesh, t < 1.0)] = 1.0  # the mouth's inside below the line turns with the head
    w = 1.0 - (1.0 - t) ** SHARE_POWER
    w[skin.stop:] = 1.0
    w[:skin.start] = 1.0
    w[mesh.fp_vertex] = 1.0  # feature points of the head turn with it in full (the standard's head rotation)
    idx = np.flatnonzero(w < 1.0)
    return idx, w[idx]


def _cut_off_from_the_cut(mesh: HeadMesh, below: np.ndarray) -> np.ndarray:
    """Skin vertices in ``below`` that no path within ``below`` joins to the neck's cut (the floor of
    the mouth's inside: joined to the neck only over the lips, which turn with the head)."""
    skin = mesh.part("skin")
    local = np.flatnonzero(below[skin])
    if not len(local):
        return local
    graph = adjacency(mesh.triangles["skin"] - skin.start, skin.stop - skin.start)[local][:, local]
    _, label = connected_components(graph, directed=False)
    y = mesh.vertices[skin, 1][local]
    held = np.unique(label[y <= y.min() + 1e-6])
    return local[~np.isin(label, held)] + skin.start
