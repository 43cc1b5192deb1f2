"""The feature-point deformer (the default): FAP values -> feature point motion -> mesh vertices.

One call per frame, vectorised: a sparse product for the translational FAPs
(only the rows of vertices some feature point reaches), then the rotations
(eyelids, tongue roll, jaw, eyeballs, head), each over its own vertices. Order
matters and is fixed: lips and brows move in the jaw's frame, the jaw and eyes
move in the head's frame, the head moves last.

A **fold guard** (:class:`FoldGuard`) watches the skin the translations moved: where some
triangle is about to turn over (brows at 400 lifting 20 mm, brows pulled down twice their
extreme), the points that move it spread their motion over wide weights
(:func:`.regions.wide_weights`) instead, by a share that grows as the triangle nears the
fold. Feature points stay exactly where the FAPs put them (the hairline, which no FAP names, slides
up with a forehead raised into it: :attr:`FoldGuard.scalp`); at the amplitudes of visemes and
expressions nothing changes.
"""
from __future__ import annotations

import sys
from collections.abc import Callable
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.spatial.distance import cdist

from mpeg4fa.face import motion
from mpeg4fa.face.couplings import PASSIVE_POINTS, SCALP_POINTS
from mpeg4fa.face.kept import kept
from mpeg4fa.face.lids import lid_drops, lid_strips, turn_lid
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.regions import LID_MARGIN_LOOPS, WIDE_REACH_MM, shortest_loop, smooth_down, wide_weights
from mpeg4fa.face.rig import CORNER_MARGIN_MM, THROAT_BOW_DEGREES, Rig

EYE_JOINT = {"eye_l": "l-eye", "eye_r": "r-eye"}
GUARD_ONSET = 0.2
"""The guard looks at a skin triangle once it keeps less than this share of its area facing its rest normal
(1 at rest, 0 edge-on, < 0 turned over); 0.15 before :meth:`FoldGuard.shares`, and raised with it the visemes'
skin moved at most 0.21 mm (E) on the generic head."""
GUARD_FULL_RATIO = 1.4
"""... and spreads the motion of the points around it over their wide weights by how far that motion has gone
past what brought the triangle to the onset (:meth:`FoldGuard.shares`): in full from this many times it on.
The share rose with the facing alone (from 0.15 to 0 before): 4 units of joy took the lip corner's triangle
through the whole ramp, and a growing smile stepped 1.0 mm in one unit at the corner (1.7 mm on ARKit), against
0.16 a unit elsewhere. The upper lids' front edges are held in the wide weights only: at 1.5 brows at 400 turned
the strip between them and the margins 6.9 degrees (4.4 at 1.4, 0 before; 5 is the test's bound)."""
_JAW_FAP = {kind: fap for fap, kind in motion.JAW.items()}  # "open" -> 3, "thrust" -> 14, "shift" -> 15


def _rotate_rows(points: np.ndarray, rows: np.ndarray, weights: np.ndarray, centre: np.ndarray,
                 rotation: np.ndarray, shift: np.ndarray | None = None) -> None:
    """Blend each row toward its rotated position by its weight (in place)."""
    step = (points[rows] - centre) @ (rotation - np.eye(3)).T
    if shift is not None:
        step += shift
    points[rows] += weights[:, None] * step


def point_motion(rig: Rig, v: np.ndarray) -> np.ndarray:
    """``(84, 3)`` feature point motion of a frame's translational FAPs, with the lips' outline kept
    around their opening: an inner lip corner (2.4/2.5, FAPs 6/7) and its outer corner (8.3/8.4,
    FAPs 53/54) never come closer across than :data:`~mpeg4fa.face.rig.CORNER_MARGIN_MM`, or the
    skin between folds over and shows its inside past the lips (a smile's 6/7 over a rounded
    viseme's 53/54 did). Where they would, each gives way in proportion to how far it was sent, so a
    lone FAP moves its own point exactly and pushes the other one ahead of it."""
    m = (rig.translate @ v).reshape(-1, 3)
    rest = rig.rest[rig.fp_vertex]
    for inner, outer in rig.corners:
        side = np.sign(rest[outer, 0] - rest[inner, 0]) or 1.0
        past = side * ((rest[inner, 0] + m[inner, 0]) - (rest[outer, 0] + m[outer, 0])) + CORNER_MARGIN_MM
        if past > 0:
            a, b = abs(m[inner, 0]), abs(m[outer, 0])
            share = a / (a + b) if a + b > 0 else 0.5  # the outer corner's share of the way
            m[outer, 0] += side * past * share
            m[inner, 0] -= side * past * (1.0 - share)
    return m


class FoldGuard:
    """Keeps skin from turning over under large translations (see the module docstring).

    ``columns`` are the points whose motion a narrow weight matrix ``(skin vertices, K)``
    spreads; their wide weights hold every other point and, for all but the eye's points, the lid
    margins. Built lazily: a face that never nears a fold never pays for the wide weights.
    """

    def __init__(self, mesh: HeadMesh, columns: np.ndarray, narrow: sp.spmatrix):
        from mpeg4fa.face.quality import skin_graph  # the crease measure's own idea of outside skin

        self.mesh, self.columns = mesh, np.asarray(columns)
        self.brows = np.array([mesh.fp_labels[c].startswith("4.") for c in self.columns], dtype=bool)
        self.skin = mesh.part("skin")
        self.narrow = sp.csc_matrix(narrow)
        graph = skin_graph(mesh)
        inside = np.zeros(mesh.n_vertices, bool)
        inside[graph.inside] = True
        moved = np.zeros(mesh.n_vertices, bool)
        moved[self.skin.start + np.unique(self.narrow.nonzero()[0])] = True
        tris = graph.triangles[~inside[graph.triangles].any(axis=1) & moved[graph.triangles].any(axis=1)]
        self.triangles = tris
        p = mesh.vertices[tris]
        n0 = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        self.rest_normal = n0 / np.maximum(np.einsum("ij,ij->i", n0, n0), 1e-12)[:, None]
        local = tris - self.skin.start
        dense = self.narrow.toarray()
        w = [dense[local[:, k]] for k in range(3)]  # (T, K) each
        # which watched triangles each column moves: (triangles, K), 1 where it does
        self.touches = ((w[0] != 0) | (w[1] != 0) | (w[2] != 0)).astype(np.float64)
        # how steeply each column's weight changes across each triangle (1/mm): a triangle whose
        # sum of |motion| x steepness stays under 1 - sqrt(GUARD_ONSET) keeps at least GUARD_ONSET of
        # its facing area (the in-plane map's singular values stay above 1 - that sum), so it is
        # not looked at
        e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        self.rest_edges = (e1, e2)
        sq = np.einsum("ij,ij->i", n0, n0)
        g0, g1, g2 = (np.cross(n0, e) / np.maximum(sq, 1e-12)[:, None] for e in (p[:, 2] - p[:, 1], -e2, e1))
        grad = (w[0][:, :, None] * g0[:, None] + w[1][:, :, None] * g1[:, None] + w[2][:, :, None] * g2[:, None])
        self.steep = sp.csr_matrix(np.linalg.norm(grad, axis=2) * self.touches)

    def _spread(self, scalp_slides: bool) -> np.ndarray:
        """:meth:`_derive_spread`, kept in the user cache (:func:`.kept.kept`): the wide weights solve a system per
        column (0.4 s for the feature-point deformer's 38 columns and as much again where the scalp slides, 1 s
        for ARKit's 72), paid on the first frame that nears a fold; read back, milliseconds."""
        from mpeg4fa.face import couplings, elastic, lids, mesh as mesh_module, regions
        mesh, narrow = self.mesh, self.narrow
        inputs = (mesh.vertices, *mesh.triangles.values(), "\n".join(mesh.triangles), np.asarray(mesh.fp_vertex),
                  "\n".join(mesh.fp_labels), repr(mesh.part_ranges), self.columns, narrow.data, narrow.indices,
                  narrow.indptr, f"scalp slides {scalp_slides}", np.asarray(mesh.lateral()))
        rules = (sys.modules[__name__], regions, lids, couplings, elastic, mesh_module)
        return kept("fold-guard", inputs, rules, lambda: self._derive_spread(scalp_slides))

    def _derive_spread(self, scalp_slides: bool) -> np.ndarray:
        """``(skin vertices, K)``: wide minus narrow weights, the hairline held or (``scalp_slides``: a raise) not,
        and in a raise the upper lids' front edges held with the margins (:func:`.lids.lid_strips`: a brow raise
        that lifted them 3-5 mm over the held margins turned the strip between to face the viewer, a dark band
        over each eye; a lowered brow pushed down onto them folded the lid skin, so only in a raise)."""
        mesh, skin = self.mesh, self.skin
        labels = [mesh.fp_labels[c] for c in self.columns]
        points = mesh.fp_vertex[self.columns] - skin.start
        scalp = SCALP_POINTS if scalp_slides else ()
        anchors = [int(v) - skin.start for i, v in enumerate(mesh.fp_vertex)
                   if skin.start <= v < skin.stop and mesh.fp_labels[i] not in PASSIVE_POINTS + scalp]
        held = np.unique(np.concatenate([anchors, [p for p, label in zip(points, labels) if label not in scalp]]))
        margins = np.concatenate([shortest_loop(mesh, loop) for loop in LID_MARGIN_LOOPS]) - skin.start
        if scalp_slides:
            margins = np.union1d(margins, lid_strips(mesh) - skin.start)
        with_margins = np.union1d(held, margins)
        reach = [SCALP_REACH_MM if scalp_slides and label.startswith("4.") else WIDE_REACH_MM for label in labels]
        holds = [held if label.startswith("3.") else with_margins for label in labels]
        if scalp_slides:  # a brow that reaches the scalp leaves the other side's forehead to its own brows
            side = mesh.lateral()[skin]
            holds = [np.union1d(h, np.flatnonzero(side * np.sign(side[q]) < -SCALP_MIDLINE_MM))
                     if r > WIDE_REACH_MM and abs(side[q]) > 1.0 else h for h, q, r in zip(holds, points, reach)]
        wide = wide_weights(mesh.vertices[skin], mesh.triangles["skin"] - skin.start, points, holds, reach)
        narrow = self.narrow.toarray()
        # where the narrow weights share the skin out whole (along the brow line between 4.1, 4.3
        # and 4.5), so do the wide ones: each point's wide weight alone sags between the points,
        # and brows raised together came out wavy
        have, need = wide.sum(axis=1), narrow.sum(axis=1)
        total = 0.5 * (have + need + np.sqrt((need - have) ** 2 + _SOFT ** 2)) - 0.5 * _SOFT  # a smooth max
        wide *= np.where(have > 0, total / np.maximum(have, 1e-12), 0.0)[:, None]
        return wide - narrow

    @cached_property
    def shift(self) -> np.ndarray:
        """``(skin vertices, K)``: wide minus narrow weights, what the guard adds per unit of share."""
        return self._spread(False)

    @cached_property
    def scalp(self) -> np.ndarray:
        """``(skin vertices, K)``: what the guard adds besides, per unit of share and of upward motion,
        where the hairline slides with the skin (:data:`.couplings.SCALP_POINTS`) and the brows' wide
        weights reach :data:`SCALP_REACH_MM`: the scalp gives way to a forehead raised into it, not to
        one pulled down (that stretches the forehead, the hairline stays). The brows' columns only: the
        correction of the ARKit deformer pulls the hairline itself back onto its target, and that is no raise."""
        return np.where(self.brows, self._spread(True) - self.shift, 0.0)

    def facing(self, p: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """Per watched triangle (or those ``rows`` of them): its posed area along its rest normal,
        over its rest area."""
        t = self.triangles if rows is None else self.triangles[rows]
        n = self.rest_normal if rows is None else self.rest_normal[rows]
        a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
        u, w = b - a, c - a  # the cross product by components: np.cross costs 4x as much here
        return ((u[:, 1] * w[:, 2] - u[:, 2] * w[:, 1]) * n[:, 0] + (u[:, 2] * w[:, 0] - u[:, 0] * w[:, 2]) * n[:, 1]
                + (u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]) * n[:, 2])

    def shares(self, p: np.ndarray, rows: np.ndarray, onset: float = GUARD_ONSET,
               full_ratio: float = GUARD_FULL_RATIO) -> np.ndarray:
        """Per watched triangle (those ``rows``, facing less than ``onset`` in ``p``): the share of its
        columns' motion to spread wide. Its skin's motion from rest, scaled by ``s``, gives a facing quadratic in
        ``s`` (1 at 0, below the onset at 1): ``s0``, where it crosses the onset, is the part of the motion the
        narrow weights may carry; the share rises smoothly from none at ``s0 = 1`` to all where the motion is
        ``full_ratio`` times the onset's, so the spread grows with the motion itself, not with the
        facing, which may pass through the whole ramp in a unit of a FAP."""
        t, n = self.triangles[rows], self.rest_normal[rows]
        e, g = self.rest_edges[0][rows], self.rest_edges[1][rows]
        d, h = p[t[:, 1]] - p[t[:, 0]] - e, p[t[:, 2]] - p[t[:, 0]] - g  # the edges' motion
        # by components, in facerig.js's order (the page's shares are these to the bit): e x h + d x g, d x h
        ex, ey, ez, gx, gy, gz = e[:, 0], e[:, 1], e[:, 2], g[:, 0], g[:, 1], g[:, 2]
        dx, dy, dz, hx, hy, hz = d[:, 0], d[:, 1], d[:, 2], h[:, 0], h[:, 1], h[:, 2]
        linear = ((ey * hz - ez * hy + dy * gz - dz * gy) * n[:, 0] + (ez * hx - ex * hz + dz * gx - dx * gz) * n[:, 1]
                  + (ex * hy - ey * hx + dx * gy - dy * gx) * n[:, 2])
        square = (dy * hz - dz * hy) * n[:, 0] + (dz * hx - dx * hz) * n[:, 1] + (dx * hy - dy * hx) * n[:, 2]
        # square s^2 + linear s + (1 - onset) = 0 has one root in (0, 1); of the stable pair k/q, q/square it is
        # k/q where linear < 0, else q/square (square < -k then): chosen by sign, not by range, which a facing
        # within rounding of the onset put a hair past 1 (the other root, clipped to 0, gave share 1 for a frame)
        k = 1.0 - onset
        disc = linear * linear - 4.0 * square * k
        q = -0.5 * (linear + np.where(linear >= 0.0, 1.0, -1.0) * np.sqrt(np.maximum(disc, 0.0)))
        with np.errstate(divide="ignore", invalid="ignore"):
            s0 = np.where(linear < 0.0, k / q, q / square)
        s0 = np.where(disc > 0.0, np.clip(np.nan_to_num(s0, nan=1.0), 0.0, 1.0), 1.0)
        return _smooth_step((1.0 - s0) / (1.0 - 1.0 / full_ratio))

    def relieve(self, p: np.ndarray, moves: np.ndarray, lift: np.ndarray | None = None) -> None:
        """Where ``p`` (the narrow weights having spread ``moves``, ``(K, 3)``) nears a fold, move the
        columns around it toward their wide weights (in place). Only the triangles some moving
        column reaches are looked at. ``lift`` (``(K, 3)``, ``moves`` unless given) is each column's own
        motion from rest: its upward share lets the scalp slide (:attr:`scalp`)."""
        size = np.sqrt(np.einsum("ij,ij->i", moves, moves))
        moving = size > 0
        rows = np.flatnonzero(self.steep @ size > 1.0 - np.sqrt(GUARD_ONSET))
        if not len(rows):
            return
        c = self.facing(p, rows)
        if c.min() >= GUARD_ONSET:
            return
        near = rows[c < GUARD_ONSET]
        share = (self.touches[near] * self.shares(p, near)[:, None]).max(axis=0)
        share[~moving] = 0.0
        if share.any():
            spread = share[:, None] * moves
            p[self.skin] += self.shift @ spread
            lift = moves if lift is None else lift
            rise = np.maximum(lift[:, 1], 0.0) / np.maximum(np.linalg.norm(lift, axis=1), 1e-300)  # its upward share
            if (rise * share)[self.brows].any():  # the scalp's columns but the brows' are 0: not built for them
                p[self.skin] += self.scalp @ (rise[:, None] * spread)


SCALP_REACH_MM = 80.0
"""Where the hairline slides (:attr:`FoldGuard.scalp`), the brows' (4.x) wide weights reach this far (the
others :data:`.regions.WIDE_REACH_MM`): brows raised twice their extreme (4.1 36 mm up) carry the forehead
and the scalp above it, the hairline 11.1-11.3 some 13 mm; within 50 mm, 10 triangles still folded between
4.1 and 11.1 on this deformer and 26 on ARKit; 70 mm left 2 on ARKit."""
SCALP_MIDLINE_MM = 28.0
"""... and a brow off the midline holds the skin beyond this distance across it (a left brow raised alone
moved skin past the right eye's centre line)."""
_SOFT = 0.05  # width of the smooth max's rounding (a weight sum)


def _smooth_step(x: np.ndarray) -> np.ndarray:
    t = np.clip(x, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


FALLBACK_ONSET = 0.15
"""Where a triangle, after the guard, keeps less than this share of its area facing its rest normal,
:func:`fall_back` starts to take the other field, ..."""
FALLBACK_FULL_RATIO = 1.2
"""... in full once the motion is this many times the onset's (:meth:`FoldGuard.shares`): the field differs by
millimetres there, so it comes in fast (1.4 left joy at 63 folding 2 triangles on ARKit; the rule by the facing
alone, from 0.15 to 0, stepped a brow pulled down twice its extreme 0.9 mm in one 63rd of it, 0.6 now)."""


def fall_back(rig: Rig, p: np.ndarray, field: Callable[[], np.ndarray], guard: FoldGuard,
              reach_mm: tuple[float, float]) -> None:
    """Where another deformer's skin ``p`` still nears a fold (a watched triangle of ``guard`` facing less
    than :data:`FALLBACK_ONSET`), blend the skin around toward ``field()`` (in place): the feature-point
    deformer's guarded field, computed only then. Each nearing triangle takes the skin within
    ``reach_mm[0]`` (mm, at rest, straight across: over the mouth and eye openings too, where both poses
    are whole) whole and fades out by ``reach_mm[1]``, by how far its motion has gone past the onset (none
    there, all from :data:`FALLBACK_FULL_RATIO` times it: continuous as the values sweep). A feature point
    stays put where ``field()`` puts it where ``p`` does (the caller's to see to: the guard holds all but the
    passive ones)."""
    c = guard.facing(p)
    near = c < FALLBACK_ONSET
    if not near.any():
        return
    severity = guard.shares(p, np.flatnonzero(near), FALLBACK_ONSET, FALLBACK_FULL_RATIO)
    skin = rig.parts["skin"]
    centres = rig.rest[guard.triangles[near]].mean(axis=1)
    full, none = reach_mm
    share = np.zeros(skin.stop - skin.start)
    for k in range(0, len(centres), 256):  # (skin vertices, 256) at a time: a stream folding everywhere stays small
        distance = cdist(rig.rest[skin], centres[k:k + 256])
        share = np.maximum(share, (smooth_down((distance - full) / (none - full)) * severity[k:k + 256]).max(axis=1))
    p[skin] += share[:, None] * (field()[skin] - p[skin])


def skin_guard(mesh: HeadMesh, rig: Rig) -> FoldGuard:
    """The feature-point deformer's guard: over the rig's skin columns."""
    skin = rig.parts["skin"]
    narrow = rig.weights[skin.start:skin.stop]
    columns = np.flatnonzero(np.asarray(abs(narrow).sum(axis=0)).ravel() > 0)
    return FoldGuard(mesh, columns, narrow[:, columns])


def apply_lids(rig: Rig, p: np.ndarray, v: np.ndarray) -> None:
    """FAPs 19-22, and the lids' follow of the eyes' pitch: turn each lid sheet (in place, :func:`.lids.lid_drops`)."""
    for fap, drop in lid_drops(rig.lids, rig.rest, v, rig.fapu.unit("IRISD")).items():
        turn_lid(p, rig.lids[fap], rig.rest, drop)


def pose_in_head_frame(rig: Rig, v: np.ndarray, *, lids: bool = True,
                       guard: FoldGuard | None = None) -> tuple[np.ndarray, dict[str, float]]:
    """Every layer but the head rotation: vertices in the head's own frame, and pupil sizes.

    ``lids=False`` leaves the lids to the caller (the ARKit deformer turns them after sculpting);
    ``guard`` (over the rig's skin columns) keeps the skin the translations move from folding.
    """
    rest = rig.rest
    p = rest.copy()
    fapu = rig.fapu

    fp_motion = point_motion(rig, v)
    if fp_motion.any():
        p[rig.moving] += rig.weights_moving @ fp_motion
        if guard is not None:
            guard.relieve(p, fp_motion[guard.columns])

    if lids:
        apply_lids(rig, p, v)

    roll = v[motion.TONGUE_ROLL - 1]
    if roll:
        axis_point = rest[rig.fp_vertex[next(iter(rig.roll_rows))]].copy()
        for rows, w, side in rig.roll_rows.values():
            centre = np.array([0.0, axis_point[1], 0.0])
            _rotate_rows(p, rows, w, centre, motion.rotation_matrix(2, side * roll * motion.ANGLE_UNIT_RAD))

    jaw_open, thrust, shift = (v[_JAW_FAP[k] - 1] for k in ("open", "thrust", "shift"))
    if jaw_open or thrust or shift:
        pivot = rest[rig.joints["mouth"]]
        chin = rest[rig.fp_vertex[rig.chin_fp]]
        angle = motion.arc_angle((chin - pivot)[1:], jaw_open * fapu.unit("MNS"))
        offset = (thrust * fapu.unit("MNS") * motion.direction(_JAW_FAP["thrust"])
                  + shift * fapu.unit("MW") * motion.direction(_JAW_FAP["shift"]))
        rows, w = rig.jaw_rows
        _rotate_rows(p, rows, w, pivot, motion.rotation_matrix(0, angle), offset)

    pupils = {}
    for eye, joint in EYE_JOINT.items():
        faps = {kind: f for f, (e, kind) in motion.EYE_ROTATION.items() if e == eye}
        yaw, pitch = v[faps["yaw"] - 1] * motion.ANGLE_UNIT_RAD, v[faps["pitch"] - 1] * motion.ANGLE_UNIT_RAD
        thrust_fap = next(f for f, e in motion.EYE_THRUST.items() if e == eye)
        push = v[thrust_fap - 1] * fapu.unit("ES")
        if yaw or pitch or push:
            s = rig.parts[eye]
            centre = rest[rig.joints[joint]]
            turn = motion.rotation_matrix(1, yaw) @ motion.rotation_matrix(0, pitch)
            p[s] = centre + (p[s] - centre) @ turn.T + push * motion.direction(thrust_fap)
            p[rig.joints[joint]] = centre + push * motion.direction(thrust_fap)
        dilate = v[next(f for f, e in motion.PUPIL.items() if e == eye) - 1]
        pupils[eye] = fapu.IRISD0 / 3.0 + dilate * fapu.unit("IRISD")
    return p, pupils


def partial_rotations(rotation: np.ndarray, shares: np.ndarray) -> np.ndarray:
    """``(n, 3, 3)``: the rotation turned only by each share of its angle, about its own axis
    (Rodrigues), so a share keeps lengths: a neck vertex turns part way, it is not pulled
    along the chord (a blend of positions shrinks a twisted neck into a fold)."""
    c = 0.5 * (np.trace(rotation) - 1.0)
    angle = float(np.arccos(np.clip(c, -1.0, 1.0)))
    skew = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0], rotation[1, 0] - rotation[0, 1]])
    if angle < 1e-12:
        return np.broadcast_to(np.eye(3), (len(shares), 3, 3)).copy()
    if np.linalg.norm(skew) > 1e-9:
        axis = skew / np.linalg.norm(skew)
    else:  # a half turn: the axis is the column of R + I with the most in it
        m = rotation + np.eye(3)
        axis = m[:, int(np.argmax(np.linalg.norm(m, axis=0)))]
        axis = axis / np.linalg.norm(axis)
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    a = np.asarray(shares, float)[:, None, None] * angle
    return np.eye(3) + np.sin(a) * k + (1.0 - np.cos(a)) * (k @ k)


def neck_bow(pitch: float, yaw: float) -> np.ndarray:
    """The part of a head rotation the whole neck takes, its cut included: the bow (pitch down) past
    :data:`~mpeg4fa.face.rig.THROAT_BOW_DEGREES`, about the yawed head's left-right axis (identity within it).
    The head's rotation is this times the rest, ``yaw @ (pitch - bow) @ roll``, which the neck shares out."""
    bow = pitch - np.radians(THROAT_BOW_DEGREES)
    if bow <= 0.0:
        return np.eye(3)
    yawed = motion.rotation_matrix(1, yaw)
    return yawed @ motion.rotation_matrix(0, bow) @ yawed.T


def apply_head_rotation(rig: Rig, p: np.ndarray, v: np.ndarray) -> None:
    """FAPs 48-50: turn the head, and the neck by its share of the turn (in place); a deep bow
    turns the whole neck by its excess (:func:`neck_bow`)."""
    rest = rig.rest
    head = {kind: fap for fap, kind in motion.HEAD.items()}
    pitch, yaw, roll_h = (v[head[k] - 1] * motion.ANGLE_UNIT_RAD for k in ("pitch", "yaw", "roll"))
    if pitch or yaw or roll_h:
        rows, w = rig.head_fade
        centre = rest[rig.fp_vertex[rig.head_fp]]
        rotation = motion.head_rotation(pitch, yaw, roll_h)
        whole = neck_bow(pitch, yaw)
        before = p[rows] - centre
        # turn everything (one product over the whole array), then the neck by its share
        p[:] = centre + (p - centre) @ rotation.T
        p[rows] = centre + np.einsum("nij,nj->ni", whole @ partial_rotations(whole.T @ rotation, w), before)


def deform(rig: Rig, values: np.ndarray, guard: FoldGuard | None = None) -> Pose:
    """Pose the face for one frame of low-level FAP values (68, FAP 1/2 columns ignored)."""
    v = np.asarray(values, dtype=np.float64)
    p, pupils = pose_in_head_frame(rig, v, guard=guard)
    apply_head_rotation(rig, p, v)
    return Pose(vertices=p, parts=rig.parts, pupil_diameter=pupils, fp_vertex=rig.fp_vertex)


def build(mesh: HeadMesh, rig: Rig):
    """The deformer as the registry builds it: the rig's smooth weights and their fold guard."""
    guard = skin_guard(mesh, rig)
    return lambda values: deform(rig, values, guard)
