"""The second deformer: the CC0 ARKit face units shape the face, feature points stay exact.

The feature-point deformer moves skin by smooth weights around each point; the
52 ARKit face units shipped with the generic head were sculpted by hand, so they
give more natural shapes between the points (a jaw that opens with the cheeks,
lips that funnel and pucker). This deformer:

1. poses the face with the feature-point deformer to get every feature point's
   target (so the FAPU semantics are the same by construction);
2. drives the face units from the FAPs through ``data/arkit_faps.csv`` (each
   unit's gain is read off the unit itself: the FAP value whose motion equals the
   unit's full motion at that FAP's feature point, along the FAP's direction); the
   units are made exactly mirror symmetric, and a unit that a one-sided FAP drives
   is cut to that side (``browInnerUp`` under FAP 31 raises the left brow only), so
   the animation is as symmetric and as one-sided as the FAPs;
3. corrects the sculpted skin so that every skin feature point lands exactly on
   its target: the residuals spread by the same smooth skin weights that the
   feature-point deformer uses (:func:`.rig.skin_weights`), for every skin point;
   where that would turn skin over (brows pulled down twice their extreme), the fold
   guard of the feature-point deformer spreads them wider (:class:`.FoldGuard`), and where
   the sculpt itself still nears a fold, the skin around takes the feature-point deformer's
   own guarded field, as much as the fold is near (:data:`FALLBACK_MM`).

Eyes, teeth and tongue come from the feature-point deformer, and so do the lids
(:mod:`.lids`, turned after the sculpt): the sculpted ``eyeBlink*`` units move
the lid in straight lines, through the eyeball, and leave the corners open. The
head turns last.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face import motion
from mpeg4fa.face.deformers.feature_points import (FoldGuard, apply_head_rotation, apply_lids, fall_back,
                                                   pose_in_head_frame, skin_guard)
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import edge_graph, smooth_down
from mpeg4fa.face.rig import CORNER_HOLD_MM, Rig, skin_weights
from mpeg4fa.spec import FAPS, N_FAPS

MIN_FULL_SCALE = 1.0  # a unit that moves a FAP's point by less than one FAPU unit does not serve it
FALLBACK_MM = (8.0, 20.0)
"""Where the sculpt nears a fold that the correction's guard cannot undo (a sculpted unit at its end and the
correction carrying the rest: brows pulled down twice their extreme turned two triangles over under the
middle brows 4.3/4.4, joy at 63 one a side at the lower lids' outer corners, disgust at 63 two fold lines),
the skin within these distances (mm, at rest: all, then less and less) of each nearing triangle takes the
feature-point deformer's guarded field, by how near it is to folding (none at :data:`.FALLBACK_ONSET`, all
from :data:`.FALLBACK_FULL_RATIO` times the motion that brought it there). On the generic head, (0, 15) mm
left brows x2 down and joy folded, (0, 20) a fold line over the upper lids, (8, 20) nothing. Only such poses pay
for the second field (joy at 63: 6 ms a pose, 2 without)."""


@dataclass(frozen=True)
class ArkitRig:
    gains: np.ndarray  # (U, 68): FAP values -> unit weights (before clipping to 0..1)
    deltas: sp.csr_matrix  # (skin vertices * 3, U)
    correction: sp.csr_matrix  # (skin vertices, n skin feature points)
    fp_local: np.ndarray  # skin feature point vertices, local to the skin part
    fp_global: np.ndarray
    unit_names: tuple[str, ...]


def _mapping() -> list[dict]:
    with (resources.files("mpeg4fa.face") / "data" / "arkit_faps.csv").open(encoding="utf-8") as f:
        return list(csv.DictReader(f))


MIDLINE_FADE_MM = 6.0
"""A two-sided unit driven by one side's FAP keeps that side: its weight fades across x = 0 over +- this."""
_FLIP_X = np.array([-1.0, 1.0, 1.0])
_SIDES = {"Left": "Right", "Right": "Left"}


def _side(mesh: HeadMesh, fap: int) -> str | None:
    """``"left"`` (the face's left, +x) or ``"right"`` for a FAP whose point is off the midline, else None."""
    d = mesh.lateral()[mesh.fp_vertex[mesh.fp_index(FAPS[fap - 1].feature_point[0])]]
    return None if abs(d) < 1.0 else ("left" if d > 0 else "right")


def _driven(unit: str, side: str | None) -> str:
    """The name of what a FAP drives: the unit, cut to the FAP's side when the FAP has one."""
    return unit if side is None else f"{unit}[{side}]"


def _shape(mesh: HeadMesh, name: str, x: np.ndarray) -> np.ndarray:
    """The deltas of a driven unit, made exactly mirror symmetric (the units were sculpted by hand,
    a few tenths of a mm asymmetric, and spill across the midline): a one-sided unit is the mean of
    itself and its partner's mirror image, a two-sided one the mean of itself and its own mirror
    image; cut to a side when one side's FAP drives it, so a left FAP moves only the left side."""
    units, mirror = mesh.face_units, mesh.mirror
    unit, _, side = name.rstrip("]").partition("[")
    own = units.dense(unit, mesh.n_vertices)
    partner = own
    for suffix, other in _SIDES.items():
        if unit.endswith(suffix):
            partner = units.dense(unit[: -len(suffix)] + other, mesh.n_vertices)
    shape = 0.5 * (own + partner[mirror] * _FLIP_X)
    if not side:
        return shape
    t = np.clip((x if side == "left" else -x) / (2 * MIDLINE_FADE_MM) + 0.5, 0.0, 1.0)
    return shape * (t * t * (3 - 2 * t))[:, None]


CORNER_REFIT_MM = (CORNER_HOLD_MM, CORNER_HOLD_MM + 6.0)
"""Around the outer lip corners (8.3/8.4) the sculpted ``jawOpen`` is replaced, within the first
distance (surface mm) and fading out by the second, by the rig's own jaw: each vertex turning by its
share of the rotation the unit gives the chin (:func:`.rig._jaw_weights` reads those shares off this
unit and holds the lips to the corner's share as far as the first distance). The sculpt has a step at
the corners (strain 2.7 over 0.3 mm edges at full weight) that a 40 degree turn with the jaw open made
the worst strain of the face, 2.2 x its floor; refitted only to 3 mm (9 mm fade), the blend folded
the lower lip 4 mm from 8.4 under yaw 40 pitch 20 once the rig held its corners."""


def refit_corners(mesh: HeadMesh, rig: Rig, shape: np.ndarray) -> np.ndarray:
    """``jawOpen``'s deltas with the lip corners re-fitted to the rig's jaw rotation (see above)."""
    skin = mesh.part("skin")
    corners = [mesh.fp_vertex[mesh.fp_index(label)] - skin.start for label in ("8.3", "8.4")]
    geo = dijkstra(edge_graph(mesh.vertices[skin], mesh.triangles["skin"] - skin.start), indices=corners,
                   min_only=True, limit=CORNER_REFIT_MM[1] + 1.0)
    near = smooth_down((geo - CORNER_REFIT_MM[0]) / (CORNER_REFIT_MM[1] - CORNER_REFIT_MM[0]))
    pivot = mesh.vertices[rig.joints["mouth"]]
    chin = mesh.fp_vertex[rig.chin_fp]
    a = (mesh.vertices[chin] - pivot)[1:]
    b = a + shape[chin, 1:]
    angle = np.arctan2(b[1], b[0]) - np.arctan2(a[1], a[0])
    rows, w = rig.jaw_rows
    share = np.zeros(mesh.n_vertices)
    share[rows] = w
    turn = share[:, None] * ((mesh.vertices - pivot) @ (motion.rotation_matrix(0, angle) - np.eye(3)).T)
    out = shape.copy()
    out[skin] += near[:, None] * (turn[skin] - shape[skin])
    return out


UNIT_CHECKS = (0.5, 1.0)
"""Weights at which a relieved unit alone must fold nothing (:func:`relieve_units`)."""
RELIEVED = ("cheekSquintLeft", "cheekSquintRight")
"""The units :func:`relieve_units` evens out. Others fold alone at full weight too (jawForward, jawLeft/Right,
mouthFunnel, mouthSmile*: 0.1-1.1 mm evened out), but relieved, FAP 17 at its eased full range folded 2 fold lines
next to 8.9 with the correction added (was none), so they stay as sculpted."""


def relieve_units(mesh: HeadMesh, dense: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The :data:`RELIEVED` units with their deltas evened out where the unit alone folds the skin
    (:func:`.fold_relief.even_out`), feature points held (their motion gives the gains). ``cheekSquint*`` is
    sculpted with the crow's feet bunched: at full weight it alone folded 6 triangles and 9 fold lines beside the
    outer eye corner, and under a cheek lift of 200 ENS (joy at 63), with the correction lifting 5.3 the rest of
    the way, 16 and 18; evened out (16 vertices, by at most 0.47 mm) none."""
    from mpeg4fa.face.fold_relief import even_out, skin_triangles
    tris = skin_triangles(mesh)
    rest, held = mesh.vertices, [np.asarray(mesh.fp_vertex, dtype=np.int64)]
    out = {}
    for name, d in dense.items():
        if name.partition("[")[0] in RELIEVED:
            d = even_out(rest, tris, [d], lambda f: (rest + w * f[0] for w in UNIT_CHECKS), held)[0]
        out[name] = d
    return out


def build_arkit_rig(mesh: HeadMesh, rig: Rig) -> ArkitRig:
    """Gains, sculpted deltas and the correction weights for one neutral face."""
    units = mesh.face_units
    if units is None:
        raise FaceError("this head has no ARKit face units", hint="use the feature-point deformer (deformer='fap')")
    skin = mesh.part("skin")
    n_skin = skin.stop - skin.start
    rows = _mapping()
    x = mesh.lateral()
    side_of = {int(r["fap"]): _side(mesh, int(r["fap"])) for r in rows}
    names = tuple(dict.fromkeys(_driven(r["unit"], side_of[int(r["fap"])]) for r in rows))
    dense = {name: _shape(mesh, name, x) for name in names}
    if "jawOpen" in dense:
        dense["jawOpen"] = refit_corners(mesh, rig, dense["jawOpen"])
    dense = relieve_units(mesh, dense)
    gains = np.zeros((len(names), N_FAPS))
    count = np.zeros(len(names))
    for r in rows:
        fap, sign = int(r["fap"]), float(r["sign"])
        name = _driven(r["unit"], side_of[fap])
        u, record = names.index(name), FAPS[fap - 1]
        point = mesh.fp_vertex[mesh.fp_index(record.feature_point[0])]
        full = float(dense[name][point] @ motion.direction(fap)) / rig.fapu.unit(record.fapu)
        if full * sign > MIN_FULL_SCALE:  # the unit moves the point the way this sign of the FAP does
            gains[u, fap - 1] += 1.0 / full
            count[u] += 1
    gains /= np.maximum(count, 1)[:, None]

    cols, rws, vals = [], [], []
    for u, name in enumerate(names):
        on = dense[name][skin]
        local = np.flatnonzero(np.abs(on).sum(axis=1))
        for axis in range(3):
            rws.append(3 * local + axis)
            cols.append(np.full(len(local), u))
            vals.append(on[local, axis])
    deltas = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rws), np.concatenate(cols))),
                           shape=(3 * n_skin, len(names)))

    on_skin = [i for i in range(len(mesh.fp_labels)) if skin.start <= mesh.fp_vertex[i] < skin.stop]
    weights = skin_weights(mesh, on_skin, on_skin)[:, on_skin]
    fp_global = mesh.fp_vertex[on_skin]
    # one column per distinct vertex (11.5 shares 11.4's): keep the first
    _, first = np.unique(fp_global, return_index=True)
    first = np.sort(first)
    correction = weights[skin][:, first].tocsr()
    return ArkitRig(gains=gains, deltas=deltas, correction=correction, fp_local=fp_global[first] - skin.start,
                    fp_global=fp_global[first], unit_names=names)


def unit_weights(arkit: ArkitRig, values: np.ndarray) -> np.ndarray:
    """Face unit weights in 0..1 for one frame of FAPs."""
    return np.clip(arkit.gains @ values, 0.0, 1.0)


def deform_arkit(rig: Rig, arkit: ArkitRig, values: np.ndarray, guard: FoldGuard | None = None,
                 fallback: FoldGuard | None = None) -> Pose:
    """Pose one frame with the sculpted face units, feature points exactly where the FAPs put them.

    ``guard`` (over the correction's columns) spreads the correction wider where it would fold skin;
    ``fallback`` (the feature-point deformer's guard; with ``guard`` only) then poses the skin around what
    still nears a fold (:data:`FALLBACK_MM`). The targets come from the feature-point deformer without its guard: the guard
    moves no named point, but the lid centres 3.13/3.14 ride on its wider skin, and pulled there they
    tented the lids (where the fallback takes its field, they ride with it: brows x2 down, 3.3 mm)."""
    v = np.asarray(values, dtype=np.float64)
    p, pupils = pose_in_head_frame(rig, v, lids=False)
    skin = rig.parts["skin"]
    sculpted = rig.rest[skin] + (arkit.deltas @ unit_weights(arkit, v)).reshape(-1, 3)
    p_target = p[arkit.fp_global]
    residual = p_target - sculpted[arkit.fp_local]
    p[skin] = sculpted + arkit.correction @ residual
    if guard is not None:
        guard.relieve(p, residual, p_target - rig.rest[arkit.fp_global])
        if fallback is not None:
            fall_back(rig, p, lambda: pose_in_head_frame(rig, v, lids=False, guard=fallback)[0], guard, FALLBACK_MM)
    apply_lids(rig, p, v)  # after sculpting: the lids turn over the eyeball as in the feature-point deformer
    apply_head_rotation(rig, p, v)
    return Pose(vertices=p, parts=rig.parts, pupil_diameter=pupils, fp_vertex=rig.fp_vertex)


@dataclass(frozen=True)
class ArkitDeformer:
    """The ARKit deformer set up for one face (its unit rig kept for inspection)."""

    rig: Rig
    arkit: ArkitRig
    guard: FoldGuard | None = None
    fallback: FoldGuard | None = None

    def __call__(self, values: np.ndarray) -> Pose:
        return deform_arkit(self.rig, self.arkit, values, self.guard, self.fallback)


def correction_guard(mesh: HeadMesh, arkit: ArkitRig) -> FoldGuard:
    """The fold guard over the correction's columns (a feature point per distinct skin vertex)."""
    first = {}
    for i, v in enumerate(mesh.fp_vertex):
        first.setdefault(int(v), i)
    return FoldGuard(mesh, np.array([first[int(v)] for v in arkit.fp_global]), arkit.correction)


def build(mesh: HeadMesh, rig: Rig) -> ArkitDeformer:
    arkit = build_arkit_rig(mesh, rig)
    return ArkitDeformer(rig, arkit, correction_guard(mesh, arkit), skin_guard(mesh, rig))
