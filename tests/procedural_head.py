"""A small procedural head for the face tests: no download, built in a few hundredths of a second.

It has everything the engine reads from a :class:`~mpeg4fa.face.mesh.HeadMesh`
and nothing else: a skin, two eyeballs, upper and lower teeth, a tongue and the
joint centres, with the 84 MPEG-4 feature points on vertices of their parts.

* **Layout**: the feature point coordinates below were read once off the
  generic head (``load_head().fp(label)``, rounded to 0.1 mm) and are pasted
  here as numbers, so that the two faces have the same proportions (and FAPU)
  while this one needs no asset. Only the face's left side and the midline are
  listed; the right side is their mirror image.
* **Skin**: a star-shaped closed surface around ``SKIN_CENTRE``: the union of an
  ellipsoid (150 x 220 x 190 mm) and a neck cylinder cut at y = 560 mm (as the
  generic head is), plus a smooth radial field that brings the surface near the
  feature points. It is sampled on a latitude-longitude grid whose rows and
  columns include the directions of the feature points (nearly equal ones
  share a line), so that every feature point is a grid vertex and is then set
  exactly to its layout position. Every vertex lies on its own ray from the
  centre, so no triangle can fold: each faces outward.
* **Symmetry**: the columns are symmetric about the x = 0 plane, the right half
  of every part is computed as the mirror image of the left half (bit for bit)
  and the triangulation is mirrored too, so ``mirror`` is exact and so is any
  weight computed from the mesh.
* **Teeth, tongue**: small closed ellipsoids built the same way; 9.8/9.10 and
  9.11/9.9 are the poles of the upper and lower teeth, 6.1 the front pole of
  the tongue, and 6.2-6.4 grid vertices set exactly.
* **Eyes**: :func:`mpeg4fa.face.asset._eyeball`, centred ``EYE_RADIUS`` behind the
  pupil, so that the pupil (3.5/3.6) is the front pole, vertex 0; its triangles are
  rewound to face outward if they do not.
* ``face_units`` is None, so the rig's jaw takes every vertex below the lip line.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.face.asset import _eyeball
from mpeg4fa.face.mesh import PARTS, HeadMesh
from mpeg4fa.spec import FEATURE_POINTS

# Feature points on the face's left side (x > 0) and on the midline (x = 0), in mm.
LAYOUT: dict[str, tuple[float, float, float]] = {
    "2.1": (0.0, 616.8, 137.8),
    "2.2": (0.0, 660.8, 155.3),
    "2.3": (0.0, 660.1, 154.0),
    "2.4": (24.4, 660.9, 140.7),
    "2.6": (15.6, 661.5, 151.6),
    "2.8": (11.1, 660.4, 151.7),
    "2.10": (0.0, 632.7, 149.9),
    "2.11": (15.1, 625.0, 142.1),
    "2.13": (43.1, 643.3, 77.6),
    "3.1": (31.4, 732.5, 136.8),
    "3.3": (31.0, 724.7, 136.1),
    "3.5": (30.8, 728.4, 136.6),
    "3.7": (43.5, 727.7, 130.8),
    "3.9": (31.6, 721.0, 140.1),
    "3.11": (20.4, 727.2, 134.6),
    "3.13": (30.6, 737.3, 140.7),
    "4.1": (16.2, 745.7, 148.9),
    "4.3": (34.0, 746.4, 142.0),
    "4.5": (47.7, 741.9, 133.4),
    "5.1": (38.5, 689.6, 139.8),
    "5.3": (45.0, 712.6, 134.7),
    "6.1": (0.0, 651.5, 138.7),
    "6.2": (0.0, 651.2, 98.2),
    "6.3": (24.0, 651.3, 100.0),
    "7.1": (0.0, 697.5, 16.1),
    "8.1": (0.0, 668.3, 160.2),
    "8.2": (0.0, 652.7, 156.2),
    "8.3": (25.9, 661.0, 141.7),
    "8.5": (14.5, 668.9, 154.8),
    "8.7": (12.8, 654.1, 151.7),
    "8.10": (8.1, 670.5, 158.8),
    "9.1": (17.3, 689.4, 148.9),
    "9.3": (0.0, 690.9, 168.1),
    "9.5": (12.2, 679.1, 151.7),
    "9.7": (7.8, 725.4, 146.8),
    "9.8": (0.0, 676.6, 151.1),
    "9.9": (0.0, 639.4, 141.2),
    "9.10": (0.0, 657.5, 146.8),
    "9.11": (0.0, 656.8, 145.2),
    "9.12": (0.0, 710.5, 158.3),
    "9.13": (9.4, 710.6, 151.3),
    "9.15": (0.0, 677.2, 155.8),
    "10.1": (74.9, 767.1, 57.4),
    "10.3": (83.6, 716.0, 34.4),
    "10.5": (74.4, 685.2, 57.2),
    "10.7": (74.7, 704.8, 60.2),
    "10.9": (75.6, 726.4, 60.2),
    "11.1": (0.0, 785.0, 147.3),
    "11.3": (37.9, 778.3, 135.3),
    "11.4": (0.0, 849.1, 69.6),
    "11.5": (0.0, 849.1, 69.6),
    "11.6": (0.0, 744.2, -39.2),
}

# Right-side feature point -> its left-side mirror image.
MIRROR_OF: dict[str, str] = {
    "2.5": "2.4", "2.7": "2.6", "2.9": "2.8", "2.12": "2.11", "2.14": "2.13",
    "3.2": "3.1", "3.4": "3.3", "3.6": "3.5", "3.8": "3.11", "3.10": "3.9", "3.12": "3.7", "3.14": "3.13",
    "4.2": "4.1", "4.4": "4.3", "4.6": "4.5", "5.2": "5.1", "5.4": "5.3", "6.4": "6.3",
    "8.4": "8.3", "8.6": "8.5", "8.8": "8.7", "8.9": "8.10",
    "9.2": "9.1", "9.4": "9.5", "9.6": "9.7", "9.14": "9.13",
    "10.2": "10.1", "10.4": "10.3", "10.6": "10.5", "10.8": "10.7", "10.10": "10.9", "11.2": "11.3",
}

# Edge rings each FAP-driven skin point moves (the generic head's values); others 0.
REACH: dict[str, int] = {
    "2.1": 6, "2.2": 6, "2.3": 6, "2.4": 6, "2.5": 6, "2.6": 6, "2.7": 6, "2.8": 6, "2.9": 6, "2.10": 6,
    "3.1": 4, "3.2": 4, "3.3": 4, "3.4": 4,
    "4.1": 7, "4.2": 7, "4.3": 7, "4.4": 7, "4.5": 7, "4.6": 7,
    "5.1": 8, "5.2": 8, "5.3": 8, "5.4": 8,
    "8.1": 6, "8.2": 6, "8.3": 6, "8.4": 6, "8.5": 6, "8.6": 6, "8.7": 6, "8.8": 6,
    "9.1": 5, "9.2": 5, "9.3": 5,
    "10.1": 6, "10.2": 6, "10.3": 6, "10.4": 6,
}

# Joint centres of the generic head (the eye centres are derived from the pupils).
JOINTS: dict[str, tuple[float, float, float]] = {
    "head": (0.0, 697.5, 16.1),
    "neck": (0.0, 589.0, 6.8),
    "mouth": (0.0, 688.5, 64.1),
    "jaw": (0.0, 619.1, 142.5),
    "tongue-1": (0.0, 639.3, 67.7),
    "tongue-2": (0.0, 647.0, 96.8),
    "tongue-3": (0.0, 650.9, 117.4),
    "tongue-4": (0.0, 649.2, 134.7),
}
JOINT_ORDER = ("head", "neck", "mouth", "jaw", "tongue-1", "tongue-2", "tongue-3", "tongue-4", "l-eye", "r-eye")

EYE_RADIUS = 12.0
SKIN_CENTRE = np.array([0.0, 735.0, 62.0])
SKIN_SEMI_AXES = np.array([75.0, 110.0, 95.0])  # x, y, z
NECK_SEMI_AXES = (52.0, 50.0)  # x, z of the neck cylinder (vertical, through the centre)
NECK_CUT_Y = 560.0
SKIN_GRID = (40, 48)  # base latitude rows (pole to pole) and longitude columns
FIELD_WIDTH = 0.15  # radians-ish (chord length) of the radial correction's Gaussian
MERGE_DEG = 0.4  # feature point directions closer than this share a grid line
CLEAR_DEG = (1.5, 2.5)  # base rows / columns this close to a feature point line are dropped

SKIN_POINTS = tuple(fp.label for fp in FEATURE_POINTS
                    if fp.label.split(".")[0] not in ("6", "7") and fp.label not in
                    ("3.5", "3.6", "9.8", "9.9", "9.10", "9.11", "11.5"))


def layout() -> dict[str, np.ndarray]:
    """All 84 feature point positions of the procedural head (right side mirrored)."""
    points = {label: np.array(xyz, dtype=np.float64) for label, xyz in LAYOUT.items()}
    for right, left in MIRROR_OF.items():
        points[right] = points[left] * np.array([-1.0, 1.0, 1.0])
    return {fp.label: points[fp.label] for fp in FEATURE_POINTS}


# -- a star-shaped closed surface on a latitude-longitude grid ---------------------------------


def _lines(base: np.ndarray, wanted: np.ndarray, merge: float, clear: float,
           pinned: tuple[float, ...] = ()) -> tuple[np.ndarray, np.ndarray]:
    """Sorted grid lines: ``wanted`` values (nearly equal ones merged) plus the ``base`` lines
    not too close to them; and the line index of each wanted value. ``pinned`` values stay
    exactly where they are (a cluster holding one takes it)."""
    order = np.argsort(wanted)
    clusters: list[list[int]] = []
    for k in order:
        if clusters and wanted[k] - wanted[clusters[-1][-1]] < merge:
            clusters[-1].append(k)
        else:
            clusters.append([k])
    values = []
    for members in clusters:
        vals = wanted[members]
        pin = [p for p in pinned if np.abs(vals - p).min() < merge]
        values.append(pin[0] if pin else float(vals.mean()))
    values = np.array(values)
    keep = [b for b in base if np.abs(values - b).min() >= clear]
    lines = np.array(sorted(set(keep) | set(values.tolist())))
    index = np.empty(len(wanted), dtype=np.int64)
    for value, members in zip(values, clusters):
        index[members] = int(np.flatnonzero(lines == value)[0])
    return lines, index


def _star_surface(centre, e1, e2, radius, rows: int, cols: int, points: dict[str, np.ndarray],
                  merge_deg: float = MERGE_DEG, clear_deg: tuple[float, float] = CLEAR_DEG):
    """A closed surface of one vertex per grid direction at ``radius(directions)`` from ``centre``.

    The frame is ``e1`` (the pole axis), ``e2`` (longitude 0), both in the x = 0 plane, and
    ``e3`` = +x, so that mirroring x is longitude -> -longitude. ``points`` (label -> xyz)
    become grid vertices at exactly those positions. Returns vertices, triangles (outward),
    corner UVs, the mirror permutation and label -> vertex index (all local to the part).
    """
    centre, e1, e2 = (np.asarray(a, dtype=np.float64) for a in (centre, e1, e2))
    e3 = np.array([1.0, 0.0, 0.0])
    labels = list(points)
    rel = np.array([points[label] for label in labels]).reshape(-1, 3) - centre
    a, b, x = rel @ e1, rel @ e2, rel @ e3
    theta = np.arctan2(np.hypot(b, x), a)
    phi = np.arctan2(x, b)
    merge, clear_row, clear_col = np.radians(merge_deg), np.radians(clear_deg[0]), np.radians(clear_deg[1])

    tiny = 1e-9
    top = theta < tiny
    bottom = theta > np.pi - tiny
    inner = ~(top | bottom)
    base_rows = np.linspace(0.0, np.pi, rows + 1)[1:-1]
    row_values, row_index = _lines(base_rows, theta[inner], merge, clear_row) if inner.any() else (base_rows, [])
    # columns: decide the left half [0, pi] (midline columns pinned at 0 and pi), mirror the rest
    base_half = np.linspace(0.0, np.pi, cols // 2 + 1)
    half_values, half_index = _lines(base_half, np.abs(phi[inner]), merge, clear_col, pinned=(0.0, np.pi)) \
        if inner.any() else (base_half, [])
    if half_values[0] != 0.0 or half_values[-1] != np.pi:
        raise AssertionError("the grid must have the midline columns 0 and pi")
    n_half = len(half_values)
    col_values = np.concatenate([half_values, 2 * np.pi - half_values[-2:0:-1]])
    n_cols = len(col_values)
    mirror_col = np.concatenate([[0], np.arange(n_cols - 1, 0, -1)])  # phi -> 2 pi - phi

    n_rows = len(row_values)
    t, p = np.meshgrid(row_values, col_values, indexing="ij")
    dirs = (np.cos(t)[..., None] * e1 + np.sin(t)[..., None] * (np.cos(p)[..., None] * e2
                                                                 + np.sin(p)[..., None] * e3))
    grid = np.empty((n_rows, n_cols, 3))
    left = dirs[:, :n_half].reshape(-1, 3)
    grid[:, :n_half] = (centre + radius(left)[:, None] * left).reshape(n_rows, n_half, 3)
    grid[:, 0, 0] = 0.0
    grid[:, n_half - 1, 0] = 0.0
    grid[:, n_half:] = grid[:, mirror_col[n_half:]] * np.array([-1.0, 1.0, 1.0])
    poles = centre + radius(np.array([e1, -e1]))[:, None] * np.array([e1, -e1])
    poles[:, 0] = 0.0
    verts = np.concatenate([poles[:1], grid.reshape(-1, 3), poles[1:]])
    last = len(verts) - 1

    def vid(i, j):
        return 1 + i * n_cols + j

    where: dict[str, int] = {}
    inner_labels = [label for label, keep in zip(labels, inner) if keep]
    for k, label in enumerate(inner_labels):
        i = int(row_index[k])
        j_half = int(half_index[k])
        j = j_half if phi[labels.index(label)] >= 0 else int(mirror_col[j_half])
        where[label] = vid(i, j)
    for label, is_top, is_bottom in zip(labels, top, bottom):
        if is_top:
            where[label] = 0
        elif is_bottom:
            where[label] = last
    if len(set(where.values())) != len(where):
        raise AssertionError("two feature points fell on one grid vertex")
    for label, v in where.items():
        verts[v] = points[label]

    mirror = np.empty(len(verts), dtype=np.int64)
    mirror[0], mirror[last] = 0, last
    ii, jj = np.meshgrid(np.arange(n_rows), np.arange(n_cols), indexing="ij")
    mirror[vid(ii, jj).ravel()] = vid(ii, mirror_col[jj]).ravel()

    tris, uv_param = [], []
    u_of = lambda j: col_values[j] / (2 * np.pi) if j < n_cols else 1.0  # noqa: E731
    v_of = lambda i: row_values[i] / np.pi  # noqa: E731
    for j in range(n_cols):
        k = j + 1  # unwrapped column for the UVs
        jn = k % n_cols
        tris.append((0, vid(0, j), vid(0, jn)))
        uv_param.append(((u_of(j) / 2 + u_of(k) / 2, 0.0), (u_of(j), v_of(0)), (u_of(k), v_of(0))))
        for i in range(n_rows - 1):
            a_, b_, c_, d_ = vid(i, j), vid(i, jn), vid(i + 1, jn), vid(i + 1, j)
            ua, ub = u_of(j), u_of(k)
            va, vb = v_of(i), v_of(i + 1)
            if j < n_half - 1:  # left half: diagonal a-c; right half: its mirror image b-d
                tris += [(a_, d_, c_), (a_, c_, b_)]
                uv_param += [((ua, va), (ua, vb), (ub, vb)), ((ua, va), (ub, vb), (ub, va))]
            else:
                tris += [(a_, d_, b_), (b_, d_, c_)]
                uv_param += [((ua, va), (ua, vb), (ub, va)), ((ub, va), (ua, vb), (ub, vb))]
        tris.append((last, vid(n_rows - 1, jn), vid(n_rows - 1, j)))
        uv_param.append(((u_of(j) / 2 + u_of(k) / 2, 1.0), (u_of(k), v_of(n_rows - 1)), (u_of(j), v_of(n_rows - 1))))
    tris = np.array(tris, dtype=np.int64)
    uvs = np.array(uv_param, dtype=np.float64)
    vol = np.einsum("ij,ij->i", verts[tris[:, 0]] - centre,
                    np.cross(verts[tris[:, 1]] - centre, verts[tris[:, 2]] - centre))
    if (vol < 0).all():
        tris, uvs = tris[:, ::-1], uvs[:, ::-1]
    elif not (vol > 0).all():
        raise AssertionError("procedural surface has triangles facing the wrong way")
    return verts, tris, uvs, mirror, where


def _outward(verts: np.ndarray, tris: np.ndarray, uvs: np.ndarray, centre: np.ndarray):
    """Triangles (and their corner UVs) of a closed convex part wound to face outward."""
    a, b, c = (verts[tris[:, k]] - centre for k in range(3))
    if np.einsum("ij,ij->i", a, np.cross(b, c)).sum() < 0:
        return tris[:, ::-1].copy(), uvs[:, ::-1].copy()
    return tris, uvs


def _ellipsoid_radius(frame: np.ndarray, semi_axes) -> callable:
    """Radius along unit directions of an ellipsoid with ``semi_axes`` along the rows of ``frame``."""
    frame = np.asarray(frame, dtype=np.float64)
    semi = np.asarray(semi_axes, dtype=np.float64)

    def radius(d):
        local = d @ frame.T
        return 1.0 / np.sqrt(((local / semi) ** 2).sum(axis=1))

    return radius


def _skin_radius(points: dict[str, np.ndarray]):
    """Head ellipsoid united with a neck cylinder, plus a smooth field through the feature points."""
    ellipsoid = _ellipsoid_radius(np.eye(3), SKIN_SEMI_AXES)
    drop = SKIN_CENTRE[1] - NECK_CUT_Y

    def base(d):
        horizontal = np.sqrt((d[:, 0] / NECK_SEMI_AXES[0]) ** 2 + (d[:, 2] / NECK_SEMI_AXES[1]) ** 2)
        with np.errstate(divide="ignore"):
            wall = np.where(horizontal > 0, 1.0 / horizontal, np.inf)
            cap = np.where(d[:, 1] < 0, drop / -d[:, 1], 0.0)
        neck = np.where(d[:, 1] < 0, np.minimum(wall, cap), 0.0)
        return np.maximum(ellipsoid(d), neck)

    rel = np.array(list(points.values())) - SKIN_CENTRE
    dist = np.linalg.norm(rel, axis=1)
    dirs = rel / dist[:, None]
    residual = dist - base(dirs)

    def kernel(u, v):
        sq = ((u[:, None, :] - v[None, :, :]) ** 2).sum(-1)
        return np.exp(-sq / (2 * FIELD_WIDTH ** 2))

    k = kernel(dirs, dirs)
    weights = np.linalg.solve(k + 1e-2 * np.eye(len(k)), residual)

    def radius(d):
        r0 = base(d)
        return np.maximum(r0 + kernel(d, dirs) @ weights, 0.5 * r0)

    return radius


def _small_part(top: np.ndarray, bottom: np.ndarray, depth: float, width: float, rows=8, cols=16):
    """A slim closed ellipsoid whose poles are exactly ``top`` (vertex 0) and ``bottom`` (the last)."""
    centre = (top + bottom) / 2
    axis = top - centre
    half = float(np.linalg.norm(axis))
    e1 = axis / half
    e2 = np.array([0.0, -e1[2], e1[1]])
    if e2[2] < 0:
        e2 = -e2
    frame = np.array([e1, e2, [1.0, 0.0, 0.0]])
    return _star_surface(centre, e1, e2, _ellipsoid_radius(frame, (half, depth, width)), rows, cols,
                         {"top": top, "bottom": bottom})


def build_procedural_head() -> HeadMesh:
    """The procedural head (see the module docstring)."""
    fps = layout()
    parts: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}
    fp_vertex_local: dict[str, tuple[str, int]] = {}

    skin_points = {label: fps[label] for label in SKIN_POINTS}
    verts, tris, uvs, mirror, where = _star_surface(SKIN_CENTRE, [0.0, 1.0, 0.0], [0.0, 0.0, 1.0],
                                                    _skin_radius(skin_points), *SKIN_GRID, skin_points)
    parts["skin"] = (verts, tris, uvs, mirror)
    fp_vertex_local.update({label: ("skin", v) for label, v in where.items()})
    fp_vertex_local["11.5"] = fp_vertex_local["11.4"]

    eye_centre = {}
    for part, label, right in (("eye_l", "3.5", False), ("eye_r", "3.6", True)):
        eye_centre[part] = fps[label] - np.array([0.0, 0.0, EYE_RADIUS])
        verts, tris, uvs = _eyeball(eye_centre[part], EYE_RADIUS, mirror_x=right)
        tris, uvs = _outward(verts, np.asarray(tris), uvs, eye_centre[part])
        parts[part] = (verts, np.asarray(tris, np.int64), uvs, np.arange(len(verts)))  # mirror fixed below
        fp_vertex_local[label] = (part, 0)

    for part, top, bottom in (("teeth_upper", "9.8", "9.10"), ("teeth_lower", "9.11", "9.9")):
        verts, tris, uvs, mirror, _ = _small_part(fps[top], fps[bottom], depth=4.0, width=24.0)
        parts[part] = (verts, tris, uvs, mirror)
        fp_vertex_local[top] = (part, 0)
        fp_vertex_local[bottom] = (part, len(verts) - 1)

    tip = fps["6.1"]
    t_centre = np.array([0.0, 647.9, 100.5])
    e1 = (tip - t_centre) / np.linalg.norm(tip - t_centre)
    e2 = np.array([0.0, e1[2], -e1[1]])  # up, perpendicular to the tongue's long axis
    frame = np.array([e1, e2, [1.0, 0.0, 0.0]])
    tongue_points = {label: fps[label] for label in ("6.1", "6.2", "6.3", "6.4")}
    verts, tris, uvs, mirror, where = _star_surface(
        t_centre, e1, e2, _ellipsoid_radius(frame, (np.linalg.norm(tip - t_centre), 9.0, 26.0)), 12, 24,
        tongue_points, merge_deg=2.0, clear_deg=(6.0, 6.0))
    parts["tongue"] = (verts, tris, uvs, mirror)
    fp_vertex_local.update({label: ("tongue", v) for label, v in where.items()})

    joints_xyz = {name: np.array(xyz) for name, xyz in JOINTS.items()}
    joints_xyz["l-eye"] = eye_centre["eye_l"]
    joints_xyz["r-eye"] = eye_centre["eye_r"]
    parts["joints"] = (np.array([joints_xyz[n] for n in JOINT_ORDER]), np.zeros((0, 3), np.int64),
                       np.zeros((0, 3, 2)), np.arange(len(JOINT_ORDER)))

    vertices, ranges, triangles, corner_uvs, mirrors = [], {}, {}, {}, []
    start = 0
    for part in PARTS:
        verts, tris, uvs, mirror = parts[part]
        vertices.append(verts)
        ranges[part] = (start, start + len(verts))
        triangles[part] = (tris + start).astype(np.int32)
        corner_uvs[part] = uvs.astype(np.float32)
        mirrors.append(mirror + start)
        start += len(verts)
    mirror = np.concatenate(mirrors)
    (la, lb), (ra, rb) = ranges["eye_l"], ranges["eye_r"]
    mirror[la:lb], mirror[ra:rb] = np.arange(ra, rb), np.arange(la, lb)
    joints = {name: ranges["joints"][0] + k for k, name in enumerate(JOINT_ORDER)}
    mirror[joints["l-eye"]], mirror[joints["r-eye"]] = joints["r-eye"], joints["l-eye"]

    labels = tuple(fp.label for fp in FEATURE_POINTS)
    fp_vertex = []
    for label in labels:
        if label == "7.1":
            fp_vertex.append(joints["head"])
        else:
            part, local = fp_vertex_local[label]
            fp_vertex.append(ranges[part][0] + local)
    return HeadMesh(
        vertices=np.concatenate(vertices), part_ranges=ranges, triangles=triangles, corner_uvs=corner_uvs,
        mirror=mirror, joints=joints, fp_labels=labels, fp_vertex=np.array(fp_vertex, np.int64),
        fp_reach=np.array([REACH.get(label, 0) for label in labels], np.int64), face_units=None,
        source="procedural test head",
    )
