"""Per-vertex data for the shader's surface details, computed once on the neutral mesh.

The values live on mesh vertices, so they follow the skin and the teeth as a pose
deforms them (like the lip tint in :mod:`.materials`):

* **oral cavity** (:func:`cavity_weights`): 0 on the face, rising to 1 deep in the
  mouth bag. The bag is what the inner lip contact loop (2.2 2.6 2.4 2.8 2.3 2.9 2.5
  2.7, joined by shortest edge paths) cuts off from the rest of the skin; the weight
  grows with the distance from that loop along the surface, so the lips' inner faces
  stay lip-coloured and the inside of the mouth goes dark.
* **eyebrows** (:func:`brow_coordinates`): for each skin vertex near a brow, how far
  along it lies (0 at the inner end 4.1/4.2, 1 at the outer end 4.5/4.6) and its
  height in mm above the curve through the brow's three points; the shader draws
  the brow's shape from these, sharp at any mesh density.
* **nose wrinkle** (:func:`nose_coordinates`): for skin over the upper nose, a window (0..1)
  and a coordinate in mm that runs up the bridge and down its sides, along which the shader
  lays the creases of a wrinkled nose (disgust), as strong as :func:`mpeg4fa.face.looks.nose_wrinkle`
  says the pose draws the tip toward the bridge.
* **teeth** (:func:`tooth_coordinates`): position along the dental arch in teeth (0 on
  the midline, the integer part says which tooth, the sign which side) and height in
  mm from the incisal edge, for the gaps, rounded tips and gum line of each tooth.
* **tongue** (:func:`tongue_coordinates`): how far out to its side a vertex lies (signed, 1 at
  the edge) and how many mm behind the tip, for the mouth's shadow over it: an evenly lit tongue
  read as a flat pink slab behind the dark back teeth at three-quarter.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import LIP_CONTACT_LOOP, cut_off, edge_graph, shortest_loop, smooth_down

CAVITY_RAMP_MM = (2.0, 9.0)  # surface distance from the lip contact where the dark begins and is full
CAVITY_MIN_DEPTH_MM = 10.0  # a bag shallower than this is no mouth (a face whose lips are one surface)

BROWS = (("4.1", "4.3", "4.5"), ("4.2", "4.4", "4.6"))  # inner, top, outer; left (x > 0) then right
BROW_DEPTH_MM = 20.0  # only skin at most this far behind the brow points carries a brow
BROW_FAR = (10.0, 99.0)  # (along, |height|) of vertices that carry no brow: far outside it

NOSE_ROOT = ("9.12", "9.6", "9.7")  # nose bump and the upper edges of the nose bone
WRINKLE_SIDE_MM = (7.0, 14.0)  # |x| where the creases fade out (full inside the first)
WRINKLE_SPAN_MM = (-1.0, 14.0)  # along the bridge from the nose bump: where the creases lie
WRINKLE_SLOPE = 0.6  # the creases fall this many mm per mm toward the sides (bunny lines)

UPPER_TOOTH_MM = (8.5, 6.5, 7.5, 7.0, 6.5, 10.0, 9.0)  # mesio-distal widths from the midline
LOWER_TOOTH_MM = (5.0, 5.5, 7.0, 7.0, 7.0, 11.0, 10.5)
ARCH_BINS = 24  # directions the biting edge is sampled in
TONGUE_BIN_MM = 3.0  # depth slices in which the tongue's half width is taken


def cavity_weights(mesh: HeadMesh) -> np.ndarray:
    """0..1 per vertex: how deep inside the mouth bag a skin vertex is (0 where there is no bag)."""
    out = np.zeros(mesh.n_vertices)
    if "skin" not in mesh.triangles or not all(label in mesh.fp_labels for label in LIP_CONTACT_LOOP):
        return out
    graph = edge_graph(mesh.vertices, mesh.triangles["skin"])
    loop = np.unique(shortest_loop(mesh, LIP_CONTACT_LOOP, graph))
    inside = cut_off(graph, np.arange(*mesh.part_ranges["skin"]), loop)
    if not len(inside):
        return out
    depth = mesh.vertices[loop, 2].mean() - mesh.vertices[inside, 2].min()
    if depth < CAVITY_MIN_DEPTH_MM:
        return out
    keep = np.r_[inside, loop]
    dist = dijkstra(graph[keep][:, keep], indices=np.arange(len(inside), len(keep)), min_only=True)
    a, b = CAVITY_RAMP_MM
    out[inside] = 1.0 - smooth_down((dist[:len(inside)] - a) / (b - a))
    return out


def brow_coordinates(mesh: HeadMesh, vertices: np.ndarray) -> np.ndarray:
    """``(N, 2)``: (along, height in mm) of ``vertices`` relative to the brow on their side."""
    out = np.tile(BROW_FAR, (len(vertices), 1))
    if not all(label in mesh.fp_labels for side in BROWS for label in side):
        return out
    for sign, labels in zip((1.0, -1.0), BROWS):
        pts = np.array([mesh.fp(label) for label in labels])
        x = np.abs(pts[:, 0])
        if not (x[0] < x[1] < x[2]):
            continue  # no usable brow on this side
        curve = np.polyfit(x, pts[:, 1], 2)
        side = (vertices[:, 0] * sign > 0) | ((vertices[:, 0] == 0) & (sign > 0))
        ax = np.abs(vertices[side, 0])
        along = (ax - x[0]) / (x[2] - x[0])
        height = vertices[side, 1] - np.polyval(curve, ax)
        # behind the brow (the back of the head, the neck) no brow, and no interpolated one either:
        # a triangle from a marked vertex to one on the face stays outside ``along``'s range
        near = vertices[side, 2] >= pts[:, 2].min() - BROW_DEPTH_MM
        out[side, 0] = np.where(near, along, BROW_FAR[0])
        out[side, 1] = np.where(near, height, np.copysign(BROW_FAR[1], height)).clip(-BROW_FAR[1], BROW_FAR[1])
    return out


def nose_coordinates(mesh: HeadMesh, vertices: np.ndarray) -> np.ndarray:
    """``(N, 2)``: (window 0..1, mm along the creases' ladder) of ``vertices`` for the nose wrinkle."""
    out = np.zeros((len(vertices), 2))
    if not all(label in mesh.fp_labels for label in NOSE_ROOT):
        return out
    bump, right, left = (mesh.fp(label) for label in NOSE_ROOT)
    v = np.asarray(vertices, float)
    ax = np.abs(v[:, 0] - bump[0])
    along = v[:, 1] - bump[1] + WRINKLE_SLOPE * ax
    lo, hi = WRINKLE_SPAN_MM
    a, b = WRINKLE_SIDE_MM
    side = smooth_down((ax - a) / (b - a))
    ends = np.minimum((along - lo) / 4.0, (hi - along) / 4.0).clip(0.0, 1.0)
    front = v[:, 2] >= min(right[2], left[2]) - 6.0  # the nose's front, not the inner eye corner behind it
    out[:, 0] = np.where(front, side * ends, 0.0)
    out[:, 1] = along
    return out


def tooth_coordinates(vertices: np.ndarray, upper: bool) -> np.ndarray:
    """``(N, 2)``: (signed tooth coordinate along the arch, mm from the biting edge) of one dental arch.

    The arch is the biting edge seen from above (in each direction from the arch's
    back, the lowest upper / highest lower vertex), smoothed; each vertex takes the
    arc length of its nearest point on it, so gaps run across the teeth on each face.
    """
    v = np.asarray(vertices, float)
    if len(v) < 3:
        return np.zeros((len(v), 2))
    centre_z = v[:, 2].min()
    phi = np.arctan2(v[:, 0], v[:, 2] - centre_z + 1e-9)  # 0 straight ahead, +-pi/2 at the back
    which = np.clip(((phi + np.pi / 2) / np.pi * ARCH_BINS).astype(int), 0, ARCH_BINS - 1)
    contour, bite = [], []
    for k in np.unique(which):
        sel = np.flatnonzero(which == k)
        edge = sel[np.argmin(v[sel, 1])] if upper else sel[np.argmax(v[sel, 1])]
        contour.append(v[edge, [0, 2]])
        bite.append(v[edge, 1])
    contour, bite = np.array(contour), np.array(bite)
    if len(contour) < 3:
        return np.zeros((len(v), 2))
    contour[1:-1] = (contour[:-2] + 2 * contour[1:-1] + contour[2:]) / 4
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(contour, axis=0), axis=1))]
    a, b = contour[:-1], contour[1:]
    ab = b - a

    def arc_at(xz: np.ndarray) -> np.ndarray:  # arc length of the nearest contour point
        p = xz[:, None, :]
        t = np.clip(((p - a) * ab).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0)
        seg = np.linalg.norm(p - (a + t[..., None] * ab), axis=-1).argmin(axis=1)
        return arc[seg] + t[np.arange(len(xz)), seg] * (arc[seg + 1] - arc[seg])

    at = arc_at(v[:, [0, 2]])
    s = (at - arc_at(v[:, [0, 2]] * (-1.0, 1.0))) / 2  # from the midline, symmetric left/right
    edge = np.interp(at, arc, bite)
    widths = np.array(UPPER_TOOTH_MM if upper else LOWER_TOOTH_MM)
    bounds = np.concatenate([[0.0], np.cumsum(widths)])
    reach = np.abs(s).max()  # the half arch
    bounds *= reach / bounds[-1] if reach < bounds[-1] else 1.0
    teeth = np.interp(np.abs(s), bounds, np.arange(len(bounds)), right=len(widths))
    height = (v[:, 1] - edge) if upper else (edge - v[:, 1])
    return np.c_[np.sign(s) * teeth, np.maximum(height, 0.0)]


def tongue_coordinates(vertices: np.ndarray) -> np.ndarray:
    """``(N, 2)``: (signed share of the half width at the vertex's depth, mm behind the tip) of the tongue.

    The tip is the tongue's frontmost point (largest z); the half width is the widest ``|x|`` in each
    :data:`TONGUE_BIN_MM` slice of depth, so the edge is 1 all along however the tongue narrows to its tip.
    """
    v = np.asarray(vertices, float)
    if len(v) == 0:
        return np.zeros((0, 2))
    depth = v[:, 2].max() - v[:, 2]
    slices = (depth / TONGUE_BIN_MM).astype(int)
    widest = np.zeros(slices.max() + 1)
    np.maximum.at(widest, slices, np.abs(v[:, 0]))
    filled = np.flatnonzero(np.bincount(slices))  # slices that hold a vertex
    half = np.interp(depth, (filled + 0.5) * TONGUE_BIN_MM, widest[filled])
    side = np.where(half > 1e-6, v[:, 0] / np.maximum(half, 1e-6), 0.0)
    return np.c_[np.clip(side, -1.0, 1.0), depth]
