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
3. the **lid sheet**: skin on the lid's side of the margin, within the orbit,
   turns with the margin's ratio at its x, fading to 0 over
   :data:`LID_HEIGHT_MM` of surface distance from the margin;
4. near the corners the ratios are **evened out** where a closing lid would fold the
   skin (:mod:`.lid_folds`: the margin there climbs steeply in x, so its vertices pass the
   fixed corner as they close).

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
shuts the eye, margin on margin). With the eyes straight ahead the lids move by their FAPs
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
from mpeg4fa.face.lid_folds import CORNER_FREE_MM, even_out_lids
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import LID_MARGIN_LOOPS, edge_graph, path_through, smooth_down

LID_HEIGHT_MM = 9.0  # the lid sheet fades out over this surface distance from the margin (to the crease)
ORBIT_MARGIN_MM = 9.0  # the sheet reaches this far beyond the eyeball's radius from its centre
OVERLAP_MM = 0.3  # a closed margin reaches this far past the opposite one (but at the lid point)

FOLLOW = {"upper": (1.0, 25.0, 60.0), "lower": (0.35, 8.0, 15.0)}
"""Per lid: (share of the eyeball's pitch the lid point turns by, most degrees it turns up, most
degrees it turns down). The generic head's open upper margin sits at the top of the iris (its
opening is IRISD0), so a share under 1 bares sclera above the iris when the eye looks down and
hides the iris under the lid when it looks up (tests/render/test_gaze_lid_pixels.py's measure at
20 deg, front: sclera px per column above the iris / upper lid's share of the iris, straight
0.8 / 0.02; share 0: 17.3 / 0.48, 1/2: 8.6 / 0.20, 2/3: 5.6 / 0.14, 1: 0.1 / 0.04). The upper lid
rises 25 deg at most (further and the lid sheet bunches under the brow) and follows down to 60;
the lower one moves little."""
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


def _height_at(margin: np.ndarray, vertices: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The margin's height (y) at each x, linear between its vertices."""
    p = vertices[margin]
    order = np.argsort(p[:, 0])
    return np.interp(x, p[order, 0], p[order, 1])


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
        # closure of each margin vertex: turn to the opposite margin's height at its x
        fp_vertex = int(mesh.fp_vertex[mesh.fp_index(point)])
        drop = rest[own, 1] - _height_at(other, rest, rest[own, 0])
        # a little past the other margin, so the two close without slivers (the lid point itself is exact)
        drop += np.sign(drop) * np.where(own == fp_vertex, 0.0, OVERLAP_MM)
        closure = np.array([motion.arc_angle(rest[i, 1:] - centre[1:], d) for i, d in zip(own, drop)])
        lid_closure = closure[list(own).index(fp_vertex)]
        # a lid already on the other margin (an eye modelled shut) closes by nothing: no share to divide out
        ratio = closure / lid_closure if lid_closure != 0 else np.zeros_like(closure)

        # the sheet: skin on this lid's side of the margins, within the orbit
        ball = rest[mesh.part(eye)]  # no eyeball part: the margin's nearest vertex bounds the eye
        radius = np.linalg.norm((ball if len(ball) else rest[own]) - centre, axis=1)
        radius = radius.max() if len(ball) else radius.min()
        p = rest[skin.start:skin.stop]
        idx = np.arange(skin.start, skin.stop)
        x_lo, x_hi = rest[own, 0].min(), rest[own, 0].max()
        inside_x = (p[:, 0] > x_lo) & (p[:, 0] < x_hi)
        own_y = _height_at(own, rest, p[:, 0])
        beyond = p[:, 1] > own_y if side == "upper" else p[:, 1] < own_y
        in_front = p[:, 2] > centre[2]
        near = np.linalg.norm(p - centre, axis=1) < radius + ORBIT_MARGIN_MM
        candidates = np.setdiff1d(idx[inside_x & beyond & in_front & near], np.concatenate([own, other]))
        dist = dijkstra(graph, indices=own, min_only=True, limit=LID_HEIGHT_MM)[candidates]
        keep = np.isfinite(dist)
        rows = np.concatenate([own, candidates[keep]])
        fade = smooth_down(dist[keep] / LID_HEIGHT_MM)
        order = np.argsort(rest[own, 0])
        sheet_ratio = np.interp(rest[candidates[keep], 0], rest[own[order], 0], ratio[order]) * fade
        ratios = np.concatenate([ratio, sheet_ratio])
        anchors = [v for label, v in zip(mesh.fp_labels, mesh.fp_vertex) if label not in PASSIVE_POINTS]
        ratios[np.isin(rows, anchors) & (rows != fp_vertex)] = 0.0  # other feature points stay put
        field = np.zeros(mesh.n_vertices)
        field[rows] = ratios
        # the margin keeps its closure (the eye shuts) but for its last vertices at each corner
        corners = rest[[int(mesh.fp_vertex[mesh.fp_index(label)]) for label in (lateral, medial)]]
        closes = own[np.linalg.norm(rest[own][:, None] - corners[None], axis=2).min(axis=1) > CORNER_FREE_MM]
        raw[fap] = (field, joint, fp_vertex, np.concatenate([anchors, other, closes]).astype(np.int64))
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
    the gaze, and the gaze alone leaves at least :data:`SLIT` of the opening.
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
