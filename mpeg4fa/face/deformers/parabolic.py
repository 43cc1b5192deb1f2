"""The parabolic eye model: the feature-point deformer, except that eyeballs are fitted spheres
and each lid contour is a parabola through the eye's corners and its lid point.

**Eyeballs.** Each eye part gets its least-squares sphere (:func:`.eyes.fit_sphere`; on the
generic head the eye is a sphere to rounding). FAPs 23-26 turn the eye part rigidly about the
fitted centre (yaw about y, then pitch about x, value x AU, as the feature-point deformer),
27/28 push it forward by value x ES; pupils (29/30) are a renderer parameter, as before.

**Lids.** In the eye's frame (:class:`.eyes.EyeFrame`: x along the corner line, y the vertical
height above it) the upper contour is ``y = a (x - b)^2 + c`` through the lateral corner, the
upper lid point and the medial corner (3.7, 3.1, 3.11 on the left eye; 3.12, 3.2, 3.8 on the
right), the lower one the same through 3.3/3.4. A lid FAP (19-22) at value ``V`` closes its
lid by ``d = V x IRISD`` mm: the lid point moves vertically by exactly ``d`` (down for the
upper lid, up for the lower) and the corners stay, so the parabola becomes

    y_d(x) = y(x) + s d L(x),   L(x) = (x - x1)(x - x2) / ((m - x1)(m - x2))

(``s`` = -1 upper, +1 lower; ``L`` is 0 at the corners, 1 at the lid point): ``a`` changes by
``s d / ((m - x1)(m - x2))`` and ``c`` by ``s d h^2 / (h^2 - m^2)`` (``h`` half the corner
distance, ``m`` the lid point's frame x; ``c`` moves by ``d`` itself when the lid point is at the
apex, 0.2 % / 0.6 % more on the generic head's upper / lower lids), ``b`` stays.

The mesh's margin is not exactly that parabola (the generic upper margin is up to 2.1 mm above
it near the lateral corner, an almond shape), so a margin vertex carries its offset from the
parabola, its *residual*. Let ``D`` be the closure that brings the lid point to the opposite lid
point's height (the closing value x IRISD) and ``T(x)`` the opposite margin's height at ``x``,
:data:`.lids.OVERLAP_MM` past it. A margin vertex at ``(x, y)`` moves vertically by

* ``s d L(x)`` for ``d <= 0`` (the lid opens wider: the parabola alone, residual kept);
* ``s d L(x) + (d / D) (T(x) - y - s D L(x))`` for ``0 <= d <= D``: the parabola, plus its
  residual handed over linearly to the opposite margin's, so that at ``d = D`` the margin lies
  on the opposite margin everywhere (the closed eye shows no sliver) - which makes the height
  the straight blend ``y + (d / D)(T(x) - y)``;
* that at ``D`` plus ``s (d - D) L(x)`` beyond (the parabola again).

The lid point itself has ``L = 1`` and ``T = `` the opposite point's height, so it moves by
exactly ``s d`` in every range (FAPU semantics). The lid skin beyond the margin (the vertices of
the feature-point deformer's lid sheets, :mod:`.lids`: on the lid's side of the margin, inside
the orbit) moves by the same rule: the lid's front edge (:func:`.lids.front_edges`, where the lashes
grow) closes onto the opposite front edge as the margin does onto the opposite margin, the strip
between them goes from the margin's rate to the front edge's, and the skin beyond falls off to 0
over the rest of :data:`.lids.LID_HEIGHT_MM` of surface distance (toward brow or cheek)
(:func:`.lids.across_the_lid`).

The lids ride on the eye's pitch (FAPs 25/26) as in the feature-point deformer: the share
:func:`.lids.lid_moves` gives the gaze turns the lid sheet about the eye centre
(:func:`.lids.turn_lid`), then the lid's own FAP closes it from there by the rule above.

Lids slide over the eyeball, not through it: a moved vertex keeps its x, takes its new height,
and its depth is solved so that it stays at its distance from the eyeball centre, and at least
:data:`LID_CLEARANCE_MM` outside the eyeball (a sphere slightly larger than the eye). On a
neutral face every lid vertex already is, so the distance is kept exactly, as the rotating
lid sheets keep it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face import motion
from mpeg4fa.face.deformers.feature_points import FoldGuard, apply_head_rotation, pose_in_head_frame, skin_guard
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.eyes import EyeFrame, Parabola, Sphere, closed_by, fit_sphere, lid_parabola, middle_share
from mpeg4fa.face.lids import (LID_HEIGHT_MM, LIDS, across_the_lid, closing_drops, closing_edges,
                               front_closing_drops, lid_moves, turn_lid)
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.regions import edge_graph, path_through
from mpeg4fa.face.rig import Rig

LID_CLEARANCE_MM = 0.05  # a moved lid vertex stays at least this far outside the eyeball sphere
SPHERE_TOLERANCE = 0.05  # an eye part farther than this (relative rms to its radius) from a sphere is refused
_EYE_FAPS = sorted(motion.EYE_ROTATION) + sorted(motion.EYE_THRUST)  # 23-28: this deformer turns the eyes


@dataclass(frozen=True)
class EyeBall:
    """One eye part as a sphere, and the FAPs that turn and push it."""

    part: slice
    joint: int  # the eye joint vertex (pushed with the eye, as in the feature-point deformer)
    sphere: Sphere
    yaw: int  # FAP numbers
    pitch: int
    thrust: int


@dataclass(frozen=True)
class LidContour:
    """One lid (FAP 19-22): its parabola, the vertices it moves and their vertical rates."""

    fap: int
    side: str  # "upper" / "lower"
    sign: float  # -1: closing moves down (upper), +1: up (lower)
    frame: EyeFrame
    parabola: Parabola  # rest contour in the frame
    corners_x: tuple[float, float]  # frame x of the lateral and medial corners
    middle_x: float  # frame x of the lid point
    full: float  # mm of closure that brings the lid point to the opposite lid point's height
    margin: np.ndarray  # margin vertices, lateral corner to medial corner
    point: int  # the lid point's vertex
    rows: np.ndarray  # the lid sheet (margin, lid skin; the corners and the other margin's ends at rate 0)
    open_rate: np.ndarray  # dy per mm of closure outside 0..full (the parabola, across the lid and its fall-off)
    close_rate: np.ndarray  # dy per mm of closure inside 0..full
    centre: np.ndarray  # eyeball centre (the lid sphere's)
    min_radius: float  # eyeball radius + LID_CLEARANCE_MM

    def contour(self, d: float) -> Parabola:
        """The lid's parabola (frame coordinates) after closing by ``d`` mm."""
        return closed_by(self.parabola, self.corners_x, self.middle_x, self.sign * d)

    def lift(self, d: float) -> np.ndarray:
        """Vertical motion of each row for a closure of ``d`` mm (the piecewise rule above)."""
        inside = min(max(d, 0.0), self.full)
        outside = d - inside
        return self.close_rate * inside + self.open_rate * outside


def build_eyes(mesh: HeadMesh) -> dict[str, EyeBall]:
    """Each eye part's fitted sphere and FAPs; a part that is no sphere is refused."""
    eyes = {}
    for eye, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        part = mesh.part(eye)
        sphere = fit_sphere(mesh.vertices[part])
        if sphere.rms_residual > SPHERE_TOLERANCE * sphere.radius:
            raise FaceError(f"the {eye} part is not a sphere (rms {sphere.rms_residual:.2f} mm off the best "
                            f"sphere of radius {sphere.radius:.2f} mm)",
                            hint="use the feature-point deformer (deformer='fap'), which turns the eye about its joint")
        faps = {kind: f for f, (e, kind) in motion.EYE_ROTATION.items() if e == eye}
        thrust = next(f for f, e in motion.EYE_THRUST.items() if e == eye)
        eyes[eye] = EyeBall(part=part, joint=mesh.joints[joint], sphere=sphere, yaw=faps["yaw"],
                            pitch=faps["pitch"], thrust=thrust)
    return eyes


def build_lid_contours(mesh: HeadMesh, rig: Rig, eyes: dict[str, EyeBall]) -> dict[int, LidContour]:
    """The four lids' parabolas and per-vertex rates (see the module docstring)."""
    rest = mesh.vertices
    skin = mesh.part("skin")
    graph = edge_graph(rest, mesh.triangles["skin"])
    vid = {label: int(mesh.fp_vertex[mesh.fp_index(label)]) for label in mesh.fp_labels}
    out = {}
    for fap, (eye, _, point, opposite, lateral, medial, side) in LIDS.items():
        sign = float(motion.direction(fap)[1])  # "down" (19, 20): -1, "up" (21, 22): +1
        frame = EyeFrame.from_corners(rest[vid[lateral]], rest[vid[medial]])
        parabola = lid_parabola(frame, rest[vid[lateral]], rest[vid[point]], rest[vid[medial]])
        corners_x = (float(frame.to_frame(rest[vid[lateral]])[0]), float(frame.to_frame(rest[vid[medial]])[0]))
        middle_x = float(frame.to_frame(rest[vid[point]])[0])
        full = abs(float(rest[vid[point], 1] - rest[vid[opposite], 1]))
        if full <= 0:
            raise FaceError(f"the lid points {point} and {opposite} are at one height: the eye has no opening",
                            hint="check the lid feature points")

        own = path_through(graph, [vid[lateral], vid[point], vid[medial]])
        other = path_through(graph, [vid[lateral], vid[opposite], vid[medial]])

        def opening(vertices: np.ndarray) -> np.ndarray:  # dy per mm of opening: the parabola's share at their x
            return sign * np.clip(middle_share(rest[vertices, 0] - frame.origin[0], corners_x, middle_x), 0.0, None)

        open_m = opening(own)
        close_m = -closing_drops(rest, own, other) / full
        at_point = own == vid[point]
        open_m[at_point] = close_m[at_point] = sign  # exactly value x IRISD
        corner = np.isin(own, [vid[lateral], vid[medial]])
        open_m[corner] = close_m[corner] = 0.0

        rows = rig.lids[fap].rows  # the lid sheet: margin and lid skin (the corners, the other margin's ends)
        # the front edges close onto each other as the margins do (lids.py: a shut eye shows no strip)
        front = closing_edges(rest, skin, own, side)
        close_f = -front_closing_drops(rest, skin, front, own, other) / full
        open_f = opening(front)
        from_margin = dijkstra(graph, indices=own, min_only=True, limit=LID_HEIGHT_MM)
        open_r = across_the_lid(rest, from_margin, own, front, rows, open_m, open_f)
        close_r = across_the_lid(rest, from_margin, own, front, rows, close_m, close_f)
        on_margin = np.flatnonzero(np.isin(rows, own))
        where = {v: k for k, v in enumerate(own)}
        k = np.array([where[v] for v in rows[on_margin]], dtype=int)
        open_r[on_margin], close_r[on_margin] = open_m[k], close_m[k]
        opposite_margin = np.isin(rows, other) & ~np.isin(rows, own)  # the other lid's margin stays, as the corners do
        open_r[opposite_margin] = close_r[opposite_margin] = 0.0
        if vid[point] not in set(rows.tolist()):
            raise FaceError(f"the lid sheet of FAP {fap} lacks its lid point {point}")

        sphere = eyes[eye].sphere
        out[fap] = LidContour(fap=fap, side=side, sign=sign, frame=frame, parabola=parabola, corners_x=corners_x,
                              middle_x=middle_x, full=full, margin=own, point=vid[point], rows=rows,
                              open_rate=open_r, close_rate=close_r, centre=sphere.centre,
                              min_radius=sphere.radius + LID_CLEARANCE_MM)
    return out


def apply_lid(p: np.ndarray, lid: LidContour, d: float) -> None:
    """Close one lid by ``d`` mm (in place): new heights, depths back on each vertex's sphere."""
    rows = lid.rows
    off = p[rows] - lid.centre
    r2 = np.maximum(np.einsum("ij,ij->i", off, off), lid.min_radius ** 2)
    y = off[:, 1] + lid.lift(d)
    room = r2 - off[:, 0] ** 2  # y^2 + z^2 at this x
    y = np.clip(y, -np.sqrt(np.maximum(room, 0.0)), np.sqrt(np.maximum(room, 0.0)))
    z = np.copysign(np.sqrt(np.maximum(room - y * y, 0.0)), off[:, 2])
    p[rows, 1] = lid.centre[1] + y
    p[rows, 2] = lid.centre[2] + z


def apply_eyes(p: np.ndarray, eyes: dict[str, EyeBall], v: np.ndarray, rest: np.ndarray, es: float) -> None:
    """FAPs 23-28: turn each eye part about its sphere's centre, push it forward (in place)."""
    for eye in eyes.values():
        yaw, pitch = v[eye.yaw - 1] * motion.ANGLE_UNIT_RAD, v[eye.pitch - 1] * motion.ANGLE_UNIT_RAD
        push = v[eye.thrust - 1] * es * motion.direction(eye.thrust)
        if yaw or pitch or push.any():
            c = eye.sphere.centre
            turn = motion.rotation_matrix(1, yaw) @ motion.rotation_matrix(0, pitch)
            p[eye.part] = c + (p[eye.part] - c) @ turn.T + push
            p[eye.joint] = rest[eye.joint] + push


@dataclass(frozen=True)
class ParabolicDeformer:
    """The parabolic eye model set up for one face (eyes and lids kept for inspection)."""

    rig: Rig
    eyes: dict[str, EyeBall]
    lids: dict[int, LidContour]
    guard: FoldGuard | None = None  # the feature-point deformer's fold guard (the skin away from the eyes is its)

    def __call__(self, values: np.ndarray) -> Pose:
        v = np.asarray(values, dtype=np.float64)
        rig = self.rig
        still_eyes = v.copy()  # the eyes are this deformer's: the feature-point layers leave them at rest
        still_eyes[[f - 1 for f in _EYE_FAPS]] = 0.0
        p, pupils = pose_in_head_frame(rig, still_eyes, lids=False, guard=self.guard)
        for fap, (close, follow) in lid_moves(rig.lids, rig.rest, v, rig.fapu.unit("IRISD")).items():
            if follow:  # riding on the eye's pitch: the lid sheet turns with it, as in the feature-point deformer
                turn_lid(p, rig.lids[fap], rig.rest, follow)
            if close:  # then its own FAP closes it along the parabola (closure: down for the upper lid, up for the lower)
                apply_lid(p, self.lids[fap], -self.lids[fap].sign * close)
        apply_eyes(p, self.eyes, v, rig.rest, rig.fapu.unit("ES"))
        apply_head_rotation(rig, p, v)
        return Pose(vertices=p, parts=rig.parts, pupil_diameter=pupils, fp_vertex=rig.fp_vertex)


def build(mesh: HeadMesh, rig: Rig) -> ParabolicDeformer:
    """Fit the eyeballs, the lid parabolas and the lid rates once per face."""
    eyes = build_eyes(mesh)
    return ParabolicDeformer(rig=rig, eyes=eyes, lids=build_lid_contours(mesh, rig, eyes), guard=skin_guard(mesh, rig))
