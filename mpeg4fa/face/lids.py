"""Eyelids that close: each lid is a sheet of skin turning about its eyeball's horizontal axis.

FAPs 19-22 move the lid points 3.1-3.4 vertically by value x IRISD; at the value
that brings 3.1 to the height of 3.3 (1024 on a neutral face whose lid opening
is IRISD0) the upper lid must cover the eye, and half of that must cover half
of the iris. Weighting the lid skin by one smooth bump around 3.1 cannot do it:
the margin's corners stay up and the lid drops as a V. So the lid model is
built from the margin itself:

1. the **margins**: the shortest paths along the skin from the lateral corner
   (3.7/3.12) through the upper (3.1/3.2) or lower (3.3/3.4) lid point to the
   medial corner (3.11/3.8);
2. each margin vertex's **closure**: the rotation about the eye centre's x axis
   that brings it to the height of the opposite margin at its x, and
   :data:`OVERLAP_MM` past it (the closed eye is the two margins meeting); divided by the lid point's own closure, a
   **ratio** (1 at 3.1, falling to 0 at the corners);
3. the upper lid's **front edge** (:func:`front_edges`: where the lashes grow, in front of the margin by
   the lid's thickness: 4.3 mm at the generic head's upper lid point): its own closure, the rotation that
   brings it to the lower front edge's height (:data:`FRONT_OVERLAP_MM` past it), so that a shut eye
   is the two front edges meeting, handed over to the margin's toward the corners (:data:`FRONT_TAPER_MM`).
   With the margin's ratio alone the front edge turned about half as far as the margin (the sheet faded
   from the margin), and the strip between them, which faces down into the opening, turned to face the
   viewer: a band 3.3 mm tall across every shut eye, dark for 2.35 mm of it (tests/render/test_lid_pixels.py:
   rows under 0.7 of the skin's brightness at the middle columns, front; now none);
4. the **lid sheet**: skin on the lid's side of the margin, within the orbit: across the strip from
   the margin to the front edge its ratio goes from the margin's to the front edge's (at its x), then
   fades to 0 over the rest of :data:`LID_HEIGHT_MM` of surface distance from the margin;
5. near the corners the ratios are **evened out** where a closing lid would fold the
   skin (:mod:`.lid_folds`: the margin there climbs steeply in x, so its vertices passed the
   corner as they closed); the corners themselves, which no FAP names, and the other margin's ends take a share
   too and give a little (:func:`lid_corners`).

A frame turns the lid point by the angle that lowers it by exactly value x IRISD
(:func:`mpeg4fa.face.motion.arc_angle`) and every sheet vertex by its ratio
times that angle. Rotations about the eye centre keep every vertex at its
distance from the centre, so a lid that starts outside the eyeball never cuts
into it, at any value.

The lids also **ride on the eye's pitch** (FAPs 25/26, :func:`lid_drops`): a real upper
lid keeps its margin near the top of the iris as the eye looks up or down, and the lower
lid follows less. Each lid point turns about the eye centre by a share of the eyeball's
pitch (:data:`FOLLOW`), eased into a limit at the ends of the range, and its own FAP closes
it from there toward the opposite lid where that one now is (so a blink in any gaze still
shuts the eye, the upper front edge on the lower lid). With the eyes straight ahead the lids move by their FAPs
alone, value x IRISD.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face import motion
from mpeg4fa.face.couplings import PASSIVE_POINTS
from mpeg4fa.face.lid_folds import CORNER_FREE_MM, OTHER_FREE_MM, even_out_lids
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import LID_MARGIN_LOOPS, edge_graph, path_through, smooth_down

LID_HEIGHT_MM = 9.0  # the lid sheet fades out over this surface distance from the margin (to the crease)
ORBIT_MARGIN_MM = 9.0  # the sheet reaches this far beyond the eyeball's radius from its centre
OVERLAP_MM = 0.3  # a closed margin reaches this far past the opposite one (but at the lid point)
FRONT_OVERLAP_MM = 0.0
"""A closed lid's front edge reaches the opposite one's height: the upper lid's lies in front of the lower's
(0.6 mm at the generic head's lid points) and the margins overlap behind, so no sliver shows; further, the
front edge, 4.3 mm in front of the margin, covered two thirds of it at half closure from the three-quarter
view's 5 degrees above (the parabolic lids 0.346 of it left at 0.3 mm)."""
FRONT_TAPER_MM = (1.0, 8.0)
"""Within the first of these mm (in x) of a corner the lid closes by its margin alone, past the second by its front
edge, smoothly between (generic head, folded / fold lines at a blink of 1000 as before the front edges, 14 / 14;
(1, 5) left the skin beside the medial corner 2 more, (3, 12) closed the lid as a V, the strip showing at both
sides; with the front edges held in the evening out, 32 / 26)."""
RAY_RADIUS_MM = 1.2  # skin this close to a margin vertex's forward ray is the lid's thickness in front of it
MAX_THICKNESS_MM = 8.0  # the farthest in front of its margin a lid's front edge may be

FOLLOW = {"upper": (0.9, 25.0, 60.0), "lower": (0.35, 8.0, 15.0)}
"""Per lid: (share of the eyeball's pitch the lid point turns by, most degrees it turns up, most
degrees it turns down). The generic head's open upper margin sits at the top of the iris (its
opening is IRISD0). What the viewer sees of the lid is its front edge, 4.3 mm in front of the margin,
which turns by its own share (0.88 of the lid point's at the middle: :func:`build_lids`), so the lid
point turns by a little less than the eye: tests/render/test_gaze_lid_pixels.py's measure at 20 deg
(sclera px per column above the iris / upper lid's share of the iris; straight 0.75 / 0.024 front,
0.026 three-quarter): share 1: looking down 0.06 / 0.051 front, 0.119 of the iris hidden at
three-quarter (from 5 deg above, the front edge hides the iris top as the eye turns down under it);
0.875: 1.50 px of sclera front; 0.9: at most 1.12 px (10 deg), three-quarter 0.060, looking up
0.88 / 0.035. (Before the front edges closed onto each other, the margin was what showed: share 0:
17.3 / 0.48, 1/2: 8.6 / 0.20, 2/3: 5.6 / 0.14, 1: 0.1 / 0.04.) The upper lid rises 25 deg at most
(further and the lid sheet bunches under the brow) and follows down to 60; the lower one moves little."""
KNEE = 0.6  # the follow is linear up to this share of its limit, then eases into the limit
SLIT = 0.1  # share of the opening that a gaze alone leaves between the lid points (far down, the eye is a slit)


def _lid_table() -> dict[int, tuple[str, str, str, str, str, str, str]]:
    """Per lid FAP: (eye part, eye joint, lid point, opposite lid point, lateral corner, medial corner, side),
    read off the margin loops (:data:`.regions.LID_MARGIN_LOOPS`: upper, lateral, lower, medial)."""
    (l_up, l_lat, l_low, l_med), (r_up, r_lat, r_low, r_med) = LID_MARGIN_LOOPS
    return {
        19: ("eye_l", "l-eye", l_up, l_low, l_lat, l_med, "upper"),
        20: ("eye_r", "r-eye", r_up, r_low, r_lat, r_med, "upper"),
        21: ("eye_l", "l-eye", l_low, l_up, l_lat, l_med, "lower"),
        22: ("eye_r", "r-eye", r_low, r_up, r_lat, r_med, "lower"),
    }


LIDS = _lid_table()


@dataclass(frozen=True)
class LidSheet:
    """The skin one lid FAP turns: vertices, their share of the lid point's angle, and the pivot."""

    rows: np.ndarray     # vertex indices
    ratios: np.ndarray   # angle ratio per row (1 at the lid point)
    joint: int           # vertex index of the eye centre joint
    point: int           # vertex index of the lid's feature point (3.1 ... 3.4)


def _margin(graph: sp.csr_matrix, mesh: HeadMesh, lateral: str, middle: str, medial: str) -> np.ndarray:
    return path_through(graph, [int(mesh.fp_vertex[mesh.fp_index(label)]) for label in (lateral, middle, medial)])


def height_at(margin: np.ndarray, vertices: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The margin's height (y) at each x, linear between its vertices."""
    p = vertices[margin]
    order = np.argsort(p[:, 0])
    return np.interp(x, p[order, 0], p[order, 1])


def front_edges(rest: np.ndarray, skin: slice, rows: np.ndarray) -> np.ndarray:
    """The skin vertex furthest in front of each margin vertex (head +z) within the lid's thickness: the
    margin path runs along the rim that touches the eyeball, the lid's front edge (where lashes grow) is
    in front of it. Where that is a stray (the nose beside the medial corner), the margin vertex itself."""
    rows = np.asarray(rows)
    depth, found = np.zeros(len(rows)), rows.copy()
    if not len(rows):
        return found
    # only skin in the box the rays can reach (a few hundred vertices, not the head's thousands)
    lo = rest[rows].min(axis=0) - [RAY_RADIUS_MM, RAY_RADIUS_MM, 0.0]
    hi = rest[rows].max(axis=0) + [RAY_RADIUS_MM, RAY_RADIUS_MM, MAX_THICKNESS_MM]
    index = np.arange(skin.start, skin.stop)
    index = index[np.all((rest[index] >= lo) & (rest[index] <= hi), axis=1)]
    d = rest[index][None] - rest[rows][:, None]  # (rows, candidates, 3)
    t = d[..., 2]  # in front of the margin (head +z)
    near = (t > 0) & (t < MAX_THICKNESS_MM) & (np.hypot(d[..., 0], d[..., 1]) < RAY_RADIUS_MM)
    reach = np.where(near, t, -np.inf)
    best = np.argmax(reach, axis=1)
    hit = near.any(axis=1)
    depth[hit], found[hit] = t[hit, best[hit]], index[best[hit]]
    typical = np.median(depth)
    stray = (depth < 0.6 * typical) | (depth > 1.3 * typical)
    return np.where(stray, rows, found)


def closing_edges(rest: np.ndarray, skin: slice, margin: np.ndarray, side: str) -> np.ndarray:
    """The edge a lid closes by, per vertex of its ``margin``: an upper lid's front edge (:func:`front_edges`:
    the strip behind it faces down into the opening, dark, and showed across a shut eye); a lower lid's margin
    itself (its strip faces up, to the light, and its front edge turned with the margin folded the outer corners:
    the lower lids at 200 IRISD 2 triangles, FAP 21 eased to -600 18)."""
    return front_edges(rest, skin, margin) if side == "upper" else np.asarray(margin)


def lid_strips(mesh: HeadMesh) -> np.ndarray:
    """Skin vertex indices (of the whole mesh) of the four lid margins and the upper lids' front edges
    (:func:`closing_edges`): the strips the lids carry, which a brow raise's spread leaves in place
    (:class:`~mpeg4fa.face.deformers.feature_points.FoldGuard`)."""
    rest, skin = mesh.vertices, mesh.part("skin")
    return np.unique(np.concatenate([edges for m in lid_margins(mesh)
                                     for edges in (m.rows, closing_edges(rest, skin, m.rows, m.side))]))


def closing_drops(rest: np.ndarray, rows: np.ndarray, towards: np.ndarray, overlap: float = OVERLAP_MM,
                  exact: int | None = None) -> np.ndarray:
    """How far (mm, + down) each of ``rows`` goes to close onto the path ``towards``: to its height at the row's x
    and ``overlap`` mm past it (but for the vertex ``exact``). The one closing rule of both lid deformers."""
    drop = rest[rows, 1] - height_at(towards, rest, rest[rows, 0])
    drop += np.sign(drop) * np.where(rows == exact, 0.0, overlap)
    return drop


def front_closing_drops(rest: np.ndarray, skin: slice, front: np.ndarray, margin: np.ndarray,
                        other: np.ndarray) -> np.ndarray:
    """:func:`closing_drops` of each of a lid's ``front`` edges (:func:`closing_edges` of its ``margin``) onto the
    opposite lid's front edges (``other``: that lid's margin), :data:`FRONT_OVERLAP_MM` past them; 0 where the
    front edge is the margin itself (:func:`across_the_lid` takes the margin's value there)."""
    drops = np.zeros(len(front))
    moved = front != margin
    if moved.any():
        drops[moved] = closing_drops(rest, front[moved], front_edges(rest, skin, other), FRONT_OVERLAP_MM)
    return drops


def _turns(rest: np.ndarray, centre: np.ndarray, rows: np.ndarray, drops: np.ndarray) -> np.ndarray:
    """The angle (rad) turning each of ``rows`` about the eye centre's x axis down by its drop (mm, on its arc)."""
    return np.array([motion.arc_angle(rest[i, 1:] - centre[1:], d) for i, d in zip(rows, drops)])


def across_the_lid(rest: np.ndarray, from_margin: np.ndarray, margin: np.ndarray, front: np.ndarray,
                   rows: np.ndarray, at_margin: np.ndarray, at_front: np.ndarray) -> np.ndarray:
    """A lid's motion over its sheet (``rows``), from its value on the margin (``at_margin``, per ``margin``
    vertex) and on the front edge (``at_front``, per vertex of ``front``, :func:`closing_edges` of the margin; a
    stray's, the margin vertex itself, is the margin's): across the strip between them it goes from the one to
    the other (at its x), then fades to 0 over the rest of :data:`LID_HEIGHT_MM`; ``from_margin``: surface
    distances from the margin (per vertex of the mesh). The strip is at most half :data:`LID_HEIGHT_MM` wide
    (4.2-5.6 mm on the generic head's upper lids: a front edge past 4.5 mm closes 0.97 of its way)."""
    x, dist = rest[rows, 0], from_margin[rows]
    order, front_order = np.argsort(rest[margin, 0]), np.argsort(rest[front, 0])
    at_front = np.where(front == margin, at_margin, at_front)
    # the strip's width (surface distance) where the front edge was found (and reached), carried on past the
    # strays (a width of 0 there folded the skin beside the medial corner)
    found = ((front != margin) & np.isfinite(from_margin[front]))[front_order]
    if found.any():
        width = np.minimum(np.interp(x, rest[front[front_order][found], 0], from_margin[front[front_order][found]]),
                           0.5 * LID_HEIGHT_MM)
    else:
        width = np.zeros(len(rows))
    on_margin = np.interp(x, rest[margin[order], 0], at_margin[order])
    on_front = np.interp(x, rest[front[front_order], 0], at_front[front_order])
    # toward the corners the front edge hands over to the margin (the sheet then fades from the margin, as the
    # lid closes there onto a corner that gives little: the front edge's own closure folded the skin beside it)
    ends = rest[margin, 0].min(), rest[margin, 0].max()
    inward = np.minimum(x - ends[0], ends[1] - x)
    kept = 1.0 - smooth_down((inward - FRONT_TAPER_MM[0]) / (FRONT_TAPER_MM[1] - FRONT_TAPER_MM[0]))
    width = width * kept
    on_front = kept * on_front + (1.0 - kept) * on_margin
    across = np.where(width > 0, np.clip(dist / np.where(width > 0, width, 1.0), 0.0, 1.0), 1.0)
    value = (1.0 - across) * on_margin + across * on_front
    beyond = np.nan_to_num(np.maximum(dist - width, 0.0), posinf=LID_HEIGHT_MM)
    return value * smooth_down(beyond / (LID_HEIGHT_MM - width))


def lid_corners(fap: int) -> tuple[str, str]:
    """The eye corners (lateral, medial) of lid FAP ``fap`` (19-22). No FAP names them, and they give a little as the
    lid closes and as it rides on its eye's pitch (how far: :mod:`.lid_folds`): the lids' exception to "no other
    feature point moves"."""
    return LIDS[fap][4], LIDS[fap][5]


def build_lids(mesh: HeadMesh) -> dict[int, LidSheet]:
    """The lid sheet of each lid FAP (19-22) on a neutral face."""
    rest = mesh.vertices
    skin = mesh.part("skin")
    graph = edge_graph(rest, mesh.triangles["skin"])
    raw = {}
    for fap, (eye, joint_name, point, opposite, lateral, medial, side) in LIDS.items():
        joint = mesh.joints[joint_name]
        centre = rest[joint]
        own = _margin(graph, mesh, lateral, point, medial)
        other = _margin(graph, mesh, lateral, opposite, medial)
        # closure of each margin vertex: turn to the opposite margin's height at its x, a little past it so
        # that the two close without slivers (the lid point itself is exact); the front edges likewise
        fp_vertex = int(mesh.fp_vertex[mesh.fp_index(point)])
        closure = _turns(rest, centre, own, closing_drops(rest, own, other, exact=fp_vertex))
        lid_closure = closure[list(own).index(fp_vertex)]
        front = closing_edges(rest, skin, own, side)
        front_closure = _turns(rest, centre, front, front_closing_drops(rest, skin, front, own, other))
        # a lid already on the other margin (an eye modelled shut) closes by nothing: no share to divide out
        ratio = closure / lid_closure if lid_closure != 0 else np.zeros_like(closure)
        front_ratio = front_closure / lid_closure if lid_closure != 0 else np.zeros_like(closure)

        # the sheet: skin on this lid's side of the margins, within the orbit
        ball = rest[mesh.part(eye)]  # no eyeball part: the margin's nearest vertex bounds the eye
        radius = np.linalg.norm((ball if len(ball) else rest[own]) - centre, axis=1)
        radius = radius.max() if len(ball) else radius.min()
        p = rest[skin.start:skin.stop]
        idx = np.arange(skin.start, skin.stop)
        x_lo, x_hi = rest[own, 0].min(), rest[own, 0].max()
        inside_x = (p[:, 0] > x_lo) & (p[:, 0] < x_hi)
        own_y = height_at(own, rest, p[:, 0])
        beyond = p[:, 1] > own_y if side == "upper" else p[:, 1] < own_y
        in_front = p[:, 2] > centre[2]
        near = np.linalg.norm(p - centre, axis=1) < radius + ORBIT_MARGIN_MM
        candidates = np.setdiff1d(idx[inside_x & beyond & in_front & near], np.concatenate([own, other]))
        from_margin = dijkstra(graph, indices=own, min_only=True, limit=LID_HEIGHT_MM)
        candidates = candidates[np.isfinite(from_margin[candidates])]
        rows = np.concatenate([own, candidates])
        ratios = np.concatenate([ratio, across_the_lid(rest, from_margin, own, front, candidates, ratio, front_ratio)])
        anchors = [v for label, v in zip(mesh.fp_labels, mesh.fp_vertex) if label not in PASSIVE_POINTS]
        ratios[np.isin(rows, anchors) & (rows != fp_vertex)] = 0.0  # other feature points start at 0 (corners: below)
        field = np.zeros(mesh.n_vertices)
        field[rows] = ratios
        # the margin keeps its closure (the eye shuts) but for its last vertices at each corner
        riding = [int(mesh.fp_vertex[mesh.fp_index(label)]) for label in (lateral, medial)]
        corners = rest[riding]
        # (the front edges are not held: held, the evening out could not relax them at the medial end)
        closes = own[np.linalg.norm(rest[own][:, None] - corners[None], axis=2).min(axis=1) > CORNER_FREE_MM]
        # the other lid's margin is held but for its ends, the corners not at all: they give a little (lid_folds)
        stays = other[np.linalg.norm(rest[other][:, None] - corners[None], axis=2).min(axis=1) > OTHER_FREE_MM]
        held = np.concatenate([anchors, stays, closes]).astype(np.int64)
        raw[fap] = (field, joint, fp_vertex, held[~np.isin(held, riding)])
    pairs = ((19, 21), (20, 22))  # one eye's two lids (they close together), both eyes at once
    eyes = [(raw[upper][1], raw[upper][2], raw[lower][2]) for upper, lower in pairs]
    faps = [fap for pair in pairs for fap in pair]
    fields = even_out_lids(mesh, eyes, [raw[fap][0] for fap in faps], [raw[fap][3] for fap in faps])
    sheets = {}
    for fap, field in zip(faps, fields):
        rows = np.flatnonzero(field > 1e-4)
        sheets[fap] = LidSheet(rows=rows, ratios=field[rows], joint=raw[fap][1], point=raw[fap][2])
    return dict(sorted(sheets.items()))


def turn_lid(points: np.ndarray, sheet: LidSheet, rest: np.ndarray, drop: float) -> None:
    """Turn one lid sheet (in place) so that its feature point drops by ``drop`` mm on its arc."""
    centre = rest[sheet.joint]
    angle = motion.arc_angle(rest[sheet.point, 1:] - centre[1:], drop)
    if angle == 0.0:
        return
    a = sheet.ratios * angle
    c, s = np.cos(a), np.sin(a)
    dy = points[sheet.rows, 1] - centre[1]
    dz = points[sheet.rows, 2] - centre[2]
    points[sheet.rows, 1] = centre[1] + c * dy - s * dz
    points[sheet.rows, 2] = centre[2] + s * dy + c * dz


def _ease(angle: float, up: float, down: float) -> float:
    """``angle`` (rad, + down) up to KNEE of its limit, then easing into the limit (slope 1 at the knee)."""
    limit = math.radians(down if angle > 0 else up)
    knee = KNEE * limit
    a = abs(angle)
    if a <= knee:
        return angle
    return math.copysign(knee + (limit - knee) * math.tanh((a - knee) / (limit - knee)), angle)


def follow_drop(sheet: LidSheet, side: str, rest: np.ndarray, pitch: float) -> float:
    """How far (mm, + down) the lid point of ``sheet`` (``side`` "upper" or "lower") descends as its
    eye pitches by ``pitch`` rad (+ down)."""
    share, up, down = FOLLOW[side]
    angle = _ease(share * pitch, up, down)
    y, z = (float(rest[sheet.point, k] - rest[sheet.joint, k]) for k in (1, 2))
    return y - (y * math.cos(angle) - z * math.sin(angle))


_EYE_LIDS = tuple((eye, next(f for f, (e, kind) in motion.EYE_ROTATION.items() if e == eye and kind == "pitch"),
                   {LIDS[f][6]: f for f in LIDS if LIDS[f][0] == eye}) for eye in ("eye_l", "eye_r"))
"""Per eye: its pitch FAP (25/26) and its lid FAPs by side."""


def lid_moves(sheets: dict[int, LidSheet], rest: np.ndarray, values: np.ndarray,
              irisd: float) -> dict[int, tuple[float, float]]:
    """Per lid that moves this frame: (mm its own FAP drops its point, mm the gaze drops it), + down.

    A lid FAP alone moves its point by value x IRISD (the FAPU semantics); the eye's pitch adds
    each lid's follow (:func:`follow_drop`). A lid that its own FAP closes goes from its followed
    place toward the opposite lid's followed place: at the closing value it lies on it, whatever
    the gaze, and the gaze alone leaves at least :data:`SLIT` of the opening. Both lids closing past each other
    (a blink over a smile's raised lower lids, 19/20 at 1146 over 21/22 at 369 in a visage stream) meet instead:
    the upper stops on the lower (the lids passed through each other and folded 52 triangles, now 8).
    """
    v = np.asarray(values, dtype=np.float64)
    out = {}
    for eye, pitch_fap, faps in _EYE_LIDS:
        if not (v[pitch_fap - 1] or v[faps["upper"] - 1] or v[faps["lower"] - 1]):
            continue
        if faps["upper"] not in sheets or faps["lower"] not in sheets:
            continue
        up, low = sheets[faps["upper"]], sheets[faps["lower"]]
        pitch = float(v[pitch_fap - 1]) * motion.ANGLE_UNIT_RAD
        follow_u = follow_drop(up, "upper", rest, pitch) if pitch else 0.0
        follow_l = follow_drop(low, "lower", rest, pitch) if pitch else 0.0
        opening = float(rest[up.point, 1] - rest[low.point, 1])
        follow_u = min(follow_u, follow_l + (1.0 - SLIT) * max(opening, 0.0))
        close_u = float(v[faps["upper"] - 1]) * irisd  # mm each FAP closes its lid (down for the upper, up for the lower)
        close_l = float(v[faps["lower"] - 1]) * irisd
        t_u = min(max(close_u / opening, 0.0), 1.0) if opening > 0 else 0.0
        t_l = min(max(close_l / opening, 0.0), 1.0) if opening > 0 else 0.0
        if t_u + t_l > 1.0:  # the lids meet: the upper comes down onto the raised lower lid, never past it
            t_u = 1.0 - t_l
            close_u = t_u * opening
        moves = {faps["upper"]: (close_u, follow_u + t_u * (follow_l - follow_u)),
                 faps["lower"]: (-close_l, follow_l + t_l * (follow_u - follow_l))}
        out.update({f: m for f, m in moves.items() if m[0] or m[1]})
    return out


def lid_drops(sheets: dict[int, LidSheet], rest: np.ndarray, values: np.ndarray, irisd: float) -> dict[int, float]:
    """How far (mm, + down) each lid point moves this frame, its FAP's and its gaze's share together (:func:`lid_moves`)."""
    return {fap: close + follow for fap, (close, follow) in lid_moves(sheets, rest, values, irisd).items()}


@dataclass(frozen=True)
class LidMargin:
    """One lid's margin on the skin, lateral corner to medial corner (what lashes grow from)."""

    eye: str             # eye part, "eye_l" or "eye_r"
    side: str            # "upper" or "lower"
    rows: np.ndarray     # vertex indices in order along the margin
    joint: int           # vertex index of the eye centre joint


def lid_margins(mesh: HeadMesh) -> list[LidMargin]:
    """The four lid margins of a neutral face (the paths :func:`build_lids` turns), in the order of :data:`LIDS`.

    Kept here, next to the lid sheets, so that anything drawn along a lid's edge (the lashes,
    :mod:`mpeg4fa.render.lashes`) rides on the same vertices the lid FAPs turn.
    """
    graph = edge_graph(mesh.vertices, mesh.triangles["skin"])
    margins = []
    for _fap, (eye, joint_name, point, _opposite, lateral, medial, side) in sorted(LIDS.items()):
        rows = _margin(graph, mesh, lateral, point, medial)
        margins.append(LidMargin(eye=eye, side=side, rows=np.asarray(rows, np.int64), joint=mesh.joints[joint_name]))
    return margins
