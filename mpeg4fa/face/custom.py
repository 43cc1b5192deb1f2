"""Rig any triangle mesh that has the MPEG-4 feature points, as the generic head is rigged.

>>> head = head_from_mesh(vertices, triangles, {"2.1": 731, "3.5": 90, ...})
>>> face = FaceModel.from_mesh(vertices, triangles, points)        # the same, as a face
>>> face.deform({3: 400})                                          # FAP number -> value

``points`` maps feature point labels to vertex indices (or to ``[x, y, z]``: snapped to the
nearest vertex within :data:`SNAP_ES` x ES0, or, for the points inside the head, 3.5/3.6, 6.x,
7.1, 9.8-9.11, kept where they are as invisible points). ``parts`` optionally names triangle
groups (rows of ``triangles``): ``eye_l``, ``eye_r``, ``teeth_upper``, ``teeth_lower``,
``tongue``, ``hair``; every other triangle is skin. A skin-only mesh works.

What the generic asset carries by hand is derived here:

* **frame**: the mesh is turned into the standard's axes (x to the face's left, from 3.6 to 3.5;
  y up, from the mouth to the eyes; z out of the face): the nearest axis permutation when the
  mesh is within 30 degrees of one, else the measured frame; shifted so the midline is x = 0;
  scaled to millimetres (a power of ten that gives a human eye separation, else exactly the
  generic head's ES0), since the rig's distances are in mm. ``info["frame"]`` has the map back,
  ``info["head_vertex"]`` each source vertex's index here (its skin copy; -1 if no triangle uses it).
* **mirror**: each vertex's nearest vertex to its x-reflection in the mirrored part
  (``scipy.spatial.cKDTree``), the feature point pairs forced onto each other;
* **joints**: eye centres (the fitted eyeball spheres, :func:`.eyes.fit_sphere`, or the pupil
  an eyeball radius, 0.52 x the eye's corner distance, behind), and the jaw pivot, the head's
  rotation centre 7.1 (unless given) and the neck mapped from the generic head's
  (``data/neutral_face.csv``) by the similarity that best fits the given points;
* **jaw weights** (the generic head reads them off its jawOpen face unit): by surface distance,
  the share of the lower lip and chin against the upper lip, faded above the mouth, behind the
  jaw angle and down the neck (:func:`jaw_weights`);
* **fp_reach**: the generic head's values per label.

Missing feature points: :data:`REQUIRED` must be given (FAPU, lid margins, lip contact, chin);
any other point left out is an invisible point at its place in the fitted generic layout, so its
FAPs move no skin. The eyes' and teeth's points are found on their parts when those are named.
"""
from __future__ import annotations

import csv
from importlib import resources
from typing import Mapping, Sequence

import numpy as np
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.eyes import fit_sphere
from mpeg4fa.face.mesh import PARTS, HeadMesh
from mpeg4fa.face.regions import LID_MARGIN_LOOPS, LIP_CONTACT_LOOP, edge_graph, smooth_down
from mpeg4fa.fdp.model import MAX_COORDINATE, first_unbounded
from mpeg4fa.spec import FEATURE_POINT_MIRROR, FEATURE_POINTS

LABELS = tuple(fp.label for fp in FEATURE_POINTS)
FAPU_POINTS = ("3.1", "3.3", "3.5", "3.6", "9.15", "2.2", "8.3", "8.4")
REQUIRED = tuple(dict.fromkeys(FAPU_POINTS + tuple(LIP_CONTACT_LOOP) + LID_MARGIN_LOOPS[0] + LID_MARGIN_LOOPS[1]
                               + ("2.1",)))
"""Points a face cannot be rigged without: the FAPU's (3.1, 3.3, 3.5, 3.6, 9.15, 2.2, 8.3, 8.4), the
lip contact loop 2.2-2.9 (the mouth slit), the lid margins 3.1-3.4, 3.7, 3.8, 3.11, 3.12, and the chin 2.1
(the point open_jaw drops). All but 3.5/3.6 must be skin vertices."""
INNER = ("3.5", "3.6", "6.1", "6.2", "6.3", "6.4", "7.1", "9.8", "9.9", "9.10", "9.11")
"""Points inside the head or on the parts behind the skin: as coordinates they may stand off the mesh."""
PART_OF = {"3.5": "eye_l", "3.6": "eye_r", "9.8": "teeth_upper", "9.10": "teeth_upper",
           "9.9": "teeth_lower", "9.11": "teeth_lower", "6.1": "tongue", "6.2": "tongue", "6.3": "tongue",
           "6.4": "tongue"}
NAMED_PARTS = ("eye_l", "eye_r", "teeth_upper", "teeth_lower", "tongue", "hair")
SNAP_ES = 0.05  # a point given as coordinates snaps to a vertex this close (x ES0)
EYE_RADIUS_PER_CORNERS = 0.52  # eyeball radius / corner-to-corner distance (the generic head: 12.0 / 23.1)
AXIS_SNAP_DEG = 30.0
HUMAN_ES_MM = (40.0, 95.0)


def _template() -> dict[str, np.ndarray]:
    table = resources.files("mpeg4fa.face") / "data" / "neutral_face.csv"
    with table.open(encoding="utf-8") as f:
        return {r["name"]: np.array([float(r["x"]), float(r["y"]), float(r["z"])]) for r in csv.DictReader(f)}


def head_from_mesh(vertices, triangles, points: Mapping[str, int | Sequence[float]], parts=None, uvs=None, *,
                   name: str = "custom mesh") -> HeadMesh:
    """A :class:`HeadMesh` the rig can animate, from any triangle mesh with feature points (see the module)."""
    v = np.asarray(vertices, dtype=np.float64)
    t = np.asarray(triangles, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3 or not len(v):
        raise FaceError(f"vertices must be a finite (V, 3) array, got shape {v.shape}")
    _check_bounded(v, "vertex", "vertices")
    if t.ndim != 2 or t.shape[1] != 3 or not len(t):
        raise FaceError(f"triangles must be a (T, 3) array of vertex indices, got shape {t.shape}")
    if t.min() < 0 or t.max() >= len(v):
        raise FaceError(f"a triangle names vertex {int(t.max() if t.max() >= len(v) else t.min())}, "
                        f"but the mesh has {len(v)} vertices")
    if not np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1).any():
        raise FaceError("the mesh has no area: every triangle's corners lie on one line", where="triangles",
                        hint="give the face's surface, with its vertices where the modelling tool put them")
    if uvs is not None:
        uvs = np.asarray(uvs, dtype=np.float64)
        if uvs.shape != (len(v), 2):
            raise FaceError(f"uvs must be (V, 2) = ({len(v)}, 2), got {uvs.shape}")
        _check_bounded(uvs, "the uv of vertex", "uvs")

    part_of_tri = _triangle_parts(parts, len(t))
    given = _read_points(points, v)
    missing = [label for label in REQUIRED if label not in given]
    if missing:
        raise FaceError(f"the mesh lacks required feature point{'s' if len(missing) > 1 else ''} {', '.join(missing)}",
                        where="points", hint=f"required: {', '.join(REQUIRED)} (FAPU, lid margins, lip contact, chin)")

    # -- the standard's frame, millimetres -------------------------------------------------
    pos = {label: (v[x] if isinstance(x, int) else x) for label, x in given.items()}
    rot = _frame(pos)
    v = v @ rot.T
    pos = {k: rot @ p for k, p in pos.items()}
    mid = _midline_x(pos)
    v[:, 0] -= mid
    for p in pos.values():
        p[0] -= mid
    es = pos["3.5"][0] - pos["3.6"][0]
    if not es > 0:
        raise FaceError("3.5 and 3.6 are one point: no eye separation", where="points")
    scale = _scale(es)
    v *= scale
    pos = {k: p * scale for k, p in pos.items()}
    es *= scale

    # -- parts: each named triangle group with its own copy of its vertices ----------------
    names = ["skin"] + [p for p in PARTS if p not in ("skin", "joints")]
    out_v, ranges, tris, cuvs, local_of = [], {}, {}, {}, {}
    count = 0
    flat_uv = uvs if uvs is not None else _planar_uvs(v)
    for part in names:
        sel = part_of_tri == part if part != "skin" else np.isin(part_of_tri, ("skin", "hair"))
        pt = t[sel]
        used = np.unique(pt)
        ranges[part] = (count, count + len(used))
        tris[part] = (np.searchsorted(used, pt) + count).astype(np.int32)
        cuvs[part] = flat_uv[pt].astype(np.float32) if len(pt) else np.zeros((0, 3, 2), np.float32)
        out_v.append(v[used])
        local_of[part] = dict(zip(used.tolist(), range(count, count + len(used))))
        count += len(used)
    if ranges["skin"][0] == ranges["skin"][1]:
        raise FaceError("the mesh has no skin triangles", hint="parts name the eyes, teeth, tongue; the rest is skin")
    verts = np.concatenate(out_v)

    # eyes: the pupil first (the renderer reads an eyeball's front pole as vertex 0), the centre fitted
    eye_centre = {}
    for part, label in (("eye_l", "3.5"), ("eye_r", "3.6")):
        a, b = ranges[part]
        if b - a == 0:
            continue
        sphere = fit_sphere(verts[a:b])
        side = 1.0 if part == "eye_l" else -1.0
        if sphere.centre[0] * side <= 0:
            raise FaceError(f"part {part} lies on the face's {'right' if side > 0 else 'left'} (x {sphere.centre[0]:.1f})",
                            hint="eye_l is the face's left eye, on +x (the side of 3.5)")
        eye_centre[part] = sphere.centre
        g = given.get(label)
        front = local_of[part].get(g) if isinstance(g, int) else None
        if front is None:  # the eyeball vertex straight ahead of its centre
            front = a + int(np.argmax(verts[a:b, 2] - sphere.centre[2]))
            pos[label] = verts[front].copy()
            given[label] = -1
        order = np.r_[front, np.setdiff1d(np.arange(a, b), [front])]
        remap = np.empty(b - a, np.int64)
        remap[order - a] = np.arange(a, b)
        verts[a:b] = verts[order]
        tris[part] = remap[tris[part] - a].astype(np.int32)
        local_of[part] = {k: int(remap[i - a]) for k, i in local_of[part].items()}
        local_of[part]["pupil"] = a

    # -- feature points: on their part's copy of the vertex, or invisible joint points --------
    template = _template()
    fit = _similarity(np.array([template[k] for k in pos]), np.array(list(pos.values())))
    fp_vertex: dict[str, int] = {}
    joint_points: dict[str, np.ndarray] = {}
    for label in LABELS:
        g = given.get(label)
        part = PART_OF.get(label, "skin")
        if label in ("3.5", "3.6") and part in local_of and "pupil" in local_of[part]:
            fp_vertex[label] = local_of[part]["pupil"]
            continue
        if isinstance(g, int) and g >= 0:
            for p in (part, "skin") + tuple(names):
                if g in local_of.get(p, {}):
                    fp_vertex[label] = local_of[p][g]
                    break
            else:
                g = None
                if label not in INNER:
                    raise FaceError(f"feature point {label} is vertex {given[label]}, which no triangle uses",
                                    where=f"points/{label}", hint="put it on a vertex of the surface")
                joint_points[label] = pos[label]
            if label in REQUIRED and label not in ("3.5", "3.6") and not _within(fp_vertex.get(label), ranges["skin"]):
                raise FaceError(f"feature point {label} must be a skin vertex", where=f"points/{label}")
            continue
        joint_points[label] = pos[label] if label in pos else fit(template[label][None])[0]

    # -- joints -----------------------------------------------------------------------------
    corners = {"eye_l": ("3.7", "3.11", "3.5"), "eye_r": ("3.12", "3.8", "3.6")}
    joints_xyz = {}
    for part, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        if part in eye_centre:
            joints_xyz[joint] = eye_centre[part]
        else:
            lat, med, pupil = corners[part]
            radius = EYE_RADIUS_PER_CORNERS * np.linalg.norm(pos[lat] - pos[med])
            joints_xyz[joint] = pos[pupil] - np.array([0.0, 0.0, radius])
    for name_ in ("mouth", "neck"):
        joints_xyz[name_] = fit(template[name_][None])[0] * (0.0, 1.0, 1.0)  # on the midline
    joints_xyz["jaw"] = pos["2.1"].copy()
    joints_xyz["head"] = joint_points.pop("7.1") if "7.1" in joint_points else verts[fp_vertex.pop("7.1")]
    joint_names = ["head", "neck", "mouth", "jaw", "l-eye", "r-eye"] + [f"fp-{k}" for k in joint_points]
    joint_rows = [joints_xyz[n] for n in joint_names[:6]] + list(joint_points.values())
    ja = count
    ranges["joints"] = (ja, ja + len(joint_rows))
    tris["joints"] = np.zeros((0, 3), np.int32)
    cuvs["joints"] = np.zeros((0, 3, 2), np.float32)
    verts = np.concatenate([verts, np.array(joint_rows)])
    joints = {n: ja + i for i, n in enumerate(joint_names[:6])}
    fp_vertex["7.1"] = joints["head"]
    for i, label in enumerate(joint_points):
        fp_vertex[label] = ja + 6 + i

    mirror = _mirror(verts, ranges, fp_vertex)
    reach = _reach()
    head = HeadMesh(vertices=verts, part_ranges=ranges, triangles=tris, corner_uvs=cuvs, mirror=mirror,
                    joints=joints, fp_labels=LABELS, fp_vertex=np.array([fp_vertex[k] for k in LABELS], np.int64),
                    fp_reach=np.array([reach.get(k, 0) for k in LABELS], np.int64), face_units=None,
                    source=name)
    head_vertex = np.full(len(v), -1, np.int64)  # source vertex -> its copy here (skin first)
    for part in reversed(names):
        for src, here in local_of[part].items():
            if isinstance(src, (int, np.integer)):
                head_vertex[src] = here
    info = {"frame": {"rotation": rot, "midline_x": mid, "scale": scale}, "head_vertex": head_vertex,
            "absent_points": tuple(k for k in LABELS if k not in given),
            "absent_parts": tuple(p for p in PARTS if p != "joints" and ranges[p][0] == ranges[p][1]),
            "jaw_weights": jaw_weights(head)}
    return head.with_vertices(head.vertices, **info)


def to_source(head: HeadMesh, vertices: np.ndarray) -> np.ndarray:
    """Vertices of ``head`` (e.g. a pose's) back in the frame and units of the mesh it was made from."""
    f = head.info["frame"]
    p = np.asarray(vertices, dtype=np.float64) / f["scale"]
    p[:, 0] += f["midline_x"]
    return p @ f["rotation"]


# -- pieces ----------------------------------------------------------------------------------


def _within(i, r) -> bool:
    return i is not None and r[0] <= i < r[1]


def _triangle_parts(parts, n: int) -> np.ndarray:
    out = np.full(n, "skin", dtype=object)
    for part, rows in (parts or {}).items():
        if part not in NAMED_PARTS:
            raise FaceError(f"unknown part {part!r}", where=f"parts/{part}",
                            hint=f"parts: {', '.join(NAMED_PARTS)}; the other triangles are skin")
        rows = np.asarray(rows)
        if rows.dtype == bool:
            if rows.shape != (n,):
                raise FaceError(f"part {part}: a mask of {rows.shape} for {n} triangles", where=f"parts/{part}")
            rows = np.flatnonzero(rows)
        rows = rows.astype(np.int64).ravel()
        if len(rows) and (rows.min() < 0 or rows.max() >= n):
            raise FaceError(f"part {part} names triangle {int(rows.max())}, but the mesh has {n}", where=f"parts/{part}")
        if (out[rows] != "skin").any():
            raise FaceError(f"part {part} shares triangles with part {out[rows][out[rows] != 'skin'][0]}",
                            where=f"parts/{part}")
        out[rows] = part
    return out


def _check_bounded(values: np.ndarray, what: str, where: str) -> None:
    """Refuse a row not finite or beyond MAX_COORDINATE (the mesh readers' bound) before the rig's arithmetic."""
    row = first_unbounded(values)
    if row is not None:
        raise FaceError(f"{what} {row} is at ({', '.join(f'{x:.6g}' for x in values[row])}): coordinates must be "
                        f"finite and within +-{MAX_COORDINATE:g}", where=f"{where}/{row}",
                        hint="check the values or the mesh's unit")


def _read_points(points: Mapping, v: np.ndarray) -> dict[str, int | np.ndarray]:
    """label -> vertex index, or -> coordinates (points inside the head standing off the mesh)."""
    if not isinstance(points, Mapping):
        raise FaceError("points must map feature point labels to vertex indices", where="points")
    tree = None
    out: dict[str, int | np.ndarray] = {}
    for label, value in points.items():
        if label not in LABELS:
            raise FaceError(f"{label!r} is not an MPEG-4 feature point label", where="points",
                            hint="labels look like 2.1 .. 11.6")
        if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
            if not 0 <= value < len(v):
                raise FaceError(f"feature point {label} is vertex {value}, but the mesh has {len(v)} vertices",
                                where=f"points/{label}")
            out[label] = int(value)
            continue
        p = np.asarray(value, dtype=np.float64)
        if p.shape != (3,) or first_unbounded(p[None]) is not None:
            raise FaceError(f"feature point {label} must be a vertex index or [x, y, z], got {value!r}",
                            where=f"points/{label}")
        tree = tree or cKDTree(v)
        dist, i = tree.query(p)
        out[label] = (int(i), float(dist), p)  # decided once the scale is known
    # snap coordinates: within SNAP_ES x ES0 of a vertex, else kept as coordinates (inside points only)
    def where(label):
        x = out[label]
        return v[x] if isinstance(x, int) else x[2]
    if "3.5" in out and "3.6" in out:
        es = float(np.linalg.norm(where("3.5") - where("3.6")))
        for label, x in list(out.items()):
            if isinstance(x, tuple):
                i, dist, p = x
                if dist <= SNAP_ES * es:
                    out[label] = i
                elif label in INNER:
                    out[label] = p
                else:
                    raise FaceError(f"feature point {label} is {dist:.3g} from the nearest vertex",
                                    where=f"points/{label}", hint="put it on a vertex (or give the vertex index)")
    else:
        for label, x in list(out.items()):
            if isinstance(x, tuple):
                out[label] = x[0]
    return out


def _frame(pos: dict[str, np.ndarray]) -> np.ndarray:
    """Rotation into the standard's axes: rows x (to the face's left), y (up), z (out of the face)."""
    x = pos["3.5"] - pos["3.6"]
    up = (pos["3.5"] + pos["3.6"]) / 2 - pos["2.2"]
    nx = np.linalg.norm(x)
    if nx == 0:
        raise FaceError("3.5 and 3.6 are one point: no eye separation", where="points")
    x = x / nx
    y = up - (up @ x) * x
    if np.linalg.norm(y) == 0:
        raise FaceError("the mouth (2.2) lies on the line through the pupils", where="points")
    y /= np.linalg.norm(y)
    r = np.array([x, y, np.cross(x, y)])
    snap = np.zeros((3, 3))
    for i in range(3):
        j = int(np.argmax(np.abs(r[i])))
        snap[i, j] = np.sign(r[i, j])
    if np.allclose(np.abs(snap).sum(0), 1) and np.isclose(np.linalg.det(snap), 1):
        angle = np.degrees(np.arccos(np.clip((np.trace(r @ snap.T) - 1) / 2, -1, 1)))
        if angle < AXIS_SNAP_DEG:
            return snap
    return r


def _midline_x(pos: dict[str, np.ndarray]) -> float:
    xs = []
    for label, p in pos.items():
        twin = FEATURE_POINT_MIRROR.get(label)
        if twin is None:
            xs.append(p[0])
        elif twin in pos:
            xs.append((p[0] + pos[twin][0]) / 2)
    return float(np.mean(xs))


def _scale(es: float) -> float:
    """Factor to millimetres: a power of ten that makes ES0 human, else ES0 = the generic head's."""
    generic = _template()
    target = float(generic["3.5"][0] - generic["3.6"][0])
    k = round(float(np.log10(target / es)))
    if HUMAN_ES_MM[0] <= es * 10.0 ** k <= HUMAN_ES_MM[1]:
        return 10.0 ** k
    return target / es


def _similarity(source: np.ndarray, target: np.ndarray):
    """``p -> s R p + t``, least squares from ``source`` to ``target`` (Umeyama)."""
    ms, mt = source.mean(0), target.mean(0)
    a, b = source - ms, target - mt
    u, d, vt = np.linalg.svd(b.T @ a)
    sign = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rot = u @ sign @ vt
    s = float((d * np.diag(sign)).sum() / max((a * a).sum(), 1e-12))
    return lambda p: s * np.asarray(p) @ rot.T + (mt - s * rot @ ms)


def _planar_uvs(v: np.ndarray) -> np.ndarray:
    """A front projection into the unit square (a mesh without texture coordinates)."""
    lo, hi = v[:, :2].min(0), v[:, :2].max(0)
    return (v[:, :2] - lo) / np.maximum(hi - lo, 1e-12)


def _mirror(verts: np.ndarray, ranges: dict, fp_vertex: dict[str, int]) -> np.ndarray:
    """Nearest vertex to each vertex's x-reflection, in the part that mirrors its part."""
    out = np.arange(len(verts))
    flip = verts * (-1.0, 1.0, 1.0)
    twin = {"eye_l": "eye_r", "eye_r": "eye_l"}
    for part, (a, b) in ranges.items():
        if b == a:
            continue
        ta, tb = ranges[twin.get(part, part)]
        if tb == ta:
            continue
        _, i = cKDTree(verts[ta:tb]).query(flip[a:b])
        out[a:b] = ta + i
    for label, other in FEATURE_POINT_MIRROR.items():
        out[fp_vertex[label]] = fp_vertex[other]
    return out


def _reach() -> dict[str, int]:
    table = resources.files("mpeg4fa.face") / "data" / "hm08_feature_points.csv"
    with table.open(encoding="utf-8") as f:
        return {r["fp"]: int(r["reach"] or 0) for r in csv.DictReader(f)}


def jaw_weights(head: HeadMesh) -> np.ndarray:
    """``(V,)`` share of the jaw's rotation each vertex follows (the rig's, for a head without face units).

    On the skin: the lower lip's and chin's share against the upper lip's by surface distance
    (so the mouth slit parts them), 1 below the upper lip fading to 0 at the nose's base, 0 from the
    jaw angle's depth back by 0.4 ES0 and from the chin down the neck by 0.6 ES0. The tongue follows
    the jaw; the rig sets the lower teeth and 2.1 to 1, the eyes and upper teeth to 0.
    """
    v = head.vertices
    skin = head.part("skin")
    local = v[skin]
    graph = edge_graph(local, head.triangles["skin"] - skin.start)

    def dist(labels):
        idx = [int(head.fp_vertex[head.fp_index(k)]) - skin.start for k in labels]
        idx = [i for i in idx if 0 <= i < len(local)]
        return dijkstra(graph, indices=idx, min_only=True)

    low = dist(("2.3", "2.8", "2.9", "2.1", "2.10"))
    up = dist(("2.2", "2.6", "2.7", "9.15"))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.nan_to_num(up / (up + low), nan=0.0, posinf=0.0)
    r[~np.isfinite(up) | ~np.isfinite(low)] = 0.0
    w = 1.0 - smooth_down((r - 0.35) / 0.3)
    es = head.fp("3.5")[0] - head.fp("3.6")[0]
    lip, nose = head.fp("2.2")[1], head.fp("9.15")[1]
    top = lip + 0.25 * (nose - lip)
    w *= smooth_down((local[:, 1] - top) / max(nose + 0.5 * (nose - lip) - top, 1e-9))
    back = 0.5 * (head.fp("2.13")[2] + head.fp("2.14")[2])
    w *= 1.0 - smooth_down((local[:, 2] - (back - 0.4 * es)) / (0.4 * es))
    w *= smooth_down((head.fp("2.1")[1] - local[:, 1]) / (0.6 * es))
    out = np.zeros(len(v))
    out[skin] = w
    out[head.part("tongue")] = 1.0
    return out
