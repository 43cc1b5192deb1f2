"""The head the browser pages pose from FAPs themselves: a GLB at rest plus the face engine's rig as data.

The pages (``static/fbaplayer.html``, the live ``static/player.html``) decode FBA with fba.js and
must show what the Python face shows for the same frame. Per-FAP morph targets summed cannot: the
feature-point deformer (:mod:`mpeg4fa.face.deformers.feature_points`) is linear only in part. It
moves the feature points by a linear map of the FAPs (``rig.translate``), then keeps each inner lip
corner inside its outer one (a rule, not a sum), spreads the points' motion to the skin by a linear
map (``rig.weights``), and turns lids, tongue, jaw, eyes and head by rotations that act on the
moved vertices; the lids also follow the eyes' pitch (:func:`~mpeg4fa.face.lids.lid_moves`), and a fold
guard (:class:`~mpeg4fa.face.deformers.feature_points.FoldGuard`) spreads large translations over wide
weights where skin would turn over; before all that each FAP eases into the head's reach
(:mod:`mpeg4fa.face.reach`). So the head ships with that rig as data (:func:`rig_data`, the guard's
arrays precomputed), and ``static/js/facerig.js`` runs the same steps in the page (float64, all vertices, a few milliseconds a frame): every vertex is
where the Python face puts it, to rounding. Numbers of the standard come in already applied (FAPU x
direction in ``translate``, directions of the jaw and eye FAPs, the angle unit), never retyped.
"""
from __future__ import annotations

import json

import numpy as np

from mpeg4fa.face import lids, motion
from mpeg4fa.face.deformers import feature_points
from mpeg4fa.face.model import FaceModel
from mpeg4fa.face.reach import load_reach
from mpeg4fa.face.rig import CORNER_MARGIN_MM, THROAT_BOW_DEGREES
from mpeg4fa.spec import ANGLE_UNIT

RIG_VERSION = 6
"""Bumped when the layout of :func:`rig_data` changes (``static/js/facerig.js`` checks it)."""


def _ints(a) -> list[int]:
    return np.asarray(a, dtype=np.int64).ravel().tolist()


def _floats(a) -> list[float]:
    return np.asarray(a, dtype=np.float64).ravel().tolist()


def _sparse_rows(guard, dense: np.ndarray) -> dict:
    """A ``(skin vertices, K)`` matrix of the guard as CSR over its nonzero rows (global vertex indices)."""
    rows = np.flatnonzero(np.any(dense != 0, axis=1))
    s_rows, s_cols = np.nonzero(dense[rows])
    return {"rows": _ints(guard.skin.start + rows), "indptr": _ints(np.searchsorted(s_rows, np.arange(len(rows) + 1))),
            "indices": _ints(s_cols), "data": _floats(dense[rows][s_rows, s_cols])}


def _fold_guard(face: FaceModel) -> dict:
    """The feature-point deformer's fold guard as data: its watched triangles, each column's steepness
    over the triangles it touches (CSR by triangle), its wide-minus-narrow weights and what the sliding
    scalp adds to them for upward motion (CSR by skin vertex)."""
    guard = feature_points.skin_guard(face.mesh, face.rig)
    t_rows, t_cols = np.nonzero(guard.touches)  # row-major: CSR order
    steep = guard.steep.toarray()[t_rows, t_cols]  # 0 where a touched triangle is flat in a column: sums the same
    return {"onset": float(feature_points.GUARD_ONSET), "full_ratio": float(feature_points.GUARD_FULL_RATIO),
            "columns": _ints(guard.columns), "triangles": _ints(guard.triangles), "rest_normal": _floats(guard.rest_normal),
            "touches": {"indptr": _ints(np.searchsorted(t_rows, np.arange(len(guard.triangles) + 1))),
                        "indices": _ints(t_cols), "steep": _floats(steep)},
            "shift": _sparse_rows(guard, guard.shift), "scalp": _sparse_rows(guard, guard.scalp)}


def _gaze(face: FaceModel) -> dict:
    """The lids' follow of the eyes' pitch (:func:`~mpeg4fa.face.lids.lid_moves`) as data: per eye its pitch
    FAP and its lid FAPs, and the follow's shares, limits (degrees), knee and slit."""
    return {"eyes": [{"pitch": int(pitch), "upper": int(faps["upper"]), "lower": int(faps["lower"])}
                     for _eye, pitch, faps in lids._EYE_LIDS],
            "follow": {side: [float(x) for x in f] for side, f in lids.FOLLOW.items()},
            "knee": float(lids.KNEE), "slit": float(lids.SLIT)}


def _reach() -> dict:
    """The head's reach (:mod:`mpeg4fa.face.reach`): [positive, negative] knee and limit per FAP, null where
    the limiter leaves a FAP alone (JSON has no infinity)."""
    table = load_reach()

    def rows(a: np.ndarray) -> list[list[float | None]]:
        return [[float(x) if np.isfinite(x) else None for x in side] for side in a]

    return {"knee": rows(table.knee), "limit": rows(table.limit)}


def rig_data(face: FaceModel) -> dict:
    """The feature-point deformer's rig of ``face`` as JSON-ready data (millimetres, vertex indices of
    the face's mesh): what ``facerig.js`` needs to pose every vertex as :func:`~mpeg4fa.face.deformers.
    feature_points.deform` does."""
    rig = face.rig
    fapu = rig.fapu
    t_rows, t_faps = np.nonzero(rig.translate)
    w = rig.weights_moving.tocsr()
    jaw = {kind: fap for fap, kind in motion.JAW.items()}
    head = {kind: fap for fap, kind in motion.HEAD.items()}
    jaw_rows, jaw_w = rig.jaw_rows
    fade_rows, fade_w = rig.head_fade
    eyes = []
    for eye, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        faps = {kind: f for f, (e, kind) in motion.EYE_ROTATION.items() if e == eye}
        thrust = next(f for f, e in motion.EYE_THRUST.items() if e == eye)
        part = rig.parts[eye]
        eyes.append({"part": [part.start, part.stop], "joint": int(rig.joints[joint]), "yaw": faps["yaw"],
                     "pitch": faps["pitch"], "thrust": thrust, "thrust_dir": _floats(motion.direction(thrust))})
    roll_first = next(iter(rig.roll_rows)) if rig.roll_rows else None
    return {
        "version": RIG_VERSION, "n_vertices": int(len(rig.rest)), "rest": _floats(rig.rest),
        "fp_vertex": _ints(rig.fp_vertex), "angle_unit": float(ANGLE_UNIT),
        "translate": {"rows": _ints(t_rows), "faps": _ints(t_faps + 1), "values": _floats(rig.translate[t_rows, t_faps])},
        "corners": [[int(a), int(b)] for a, b in rig.corners], "corner_margin": float(CORNER_MARGIN_MM),
        "moving": _ints(rig.moving), "weights": {"indptr": _ints(w.indptr), "indices": _ints(w.indices),
                                                  "data": _floats(w.data)},
        "irisd": float(fapu.unit("IRISD")),
        "lids": [{"fap": int(fap), "rows": _ints(s.rows), "ratios": _floats(s.ratios), "joint": int(s.joint),
                  "point": int(s.point)} for fap, s in rig.lids.items()],
        "gaze": _gaze(face), "fold": _fold_guard(face), "reach": _reach(),
        "roll": {"fap": motion.TONGUE_ROLL, "axis_fp": None if roll_first is None else int(roll_first),
                 "parts": [{"rows": _ints(r), "weights": _floats(wt), "side": float(side)}
                           for r, wt, side in rig.roll_rows.values()]},
        "jaw": {"open": jaw["open"], "thrust": jaw["thrust"], "shift": jaw["shift"],
                "pivot": int(rig.joints["mouth"]), "chin_fp": int(rig.chin_fp), "mns": float(fapu.unit("MNS")),
                "mw": float(fapu.unit("MW")), "thrust_dir": _floats(motion.direction(jaw["thrust"])),
                "shift_dir": _floats(motion.direction(jaw["shift"])), "rows": _ints(jaw_rows), "weights": _floats(jaw_w)},
        "eyes": eyes, "es": float(fapu.unit("ES")),
        "head": {"pitch": head["pitch"], "yaw": head["yaw"], "roll": head["roll"], "fp": int(rig.head_fp),
                 "neck": "turn" if hasattr(feature_points, "partial_rotations") else "blend",
                 "fade_rows": _ints(fade_rows), "fade_weights": _floats(fade_w),
                 "throat_bow": float(THROAT_BOW_DEGREES)},
    }


def lash_data(face: FaceModel) -> dict | None:
    """How ``static/js/lashes.js`` grows the GLB's lash cards (its ``lashes`` primitive: roots, middles, tips) from the
    posed lid margins each frame, as :func:`~mpeg4fa.render.lashes.lash_vertices` does: per lash the skin vertex it
    grows from, the margin's neighbours (its tangent), the eye joint, the turn's sign, its length and the two
    halves' turns (radians). None where the face has no lid margins to grow them on."""
    from mpeg4fa.render.lashes import ROOT_OFFSET_MM, build_lashes

    layout = build_lashes(face.mesh)
    if layout is None:
        return None
    return {"rows": _ints(layout.rows), "roots": _ints(layout.roots), "before": _ints(layout.before),
            "after": _ints(layout.after), "joint": _ints(layout.joint), "sign": _floats(layout.sign),
            "length": _floats(layout.length), "lift": _floats(layout.lift), "bend": _floats(layout.bend),
            "root_offset": float(ROOT_OFFSET_MM)}


def fap_head(face: FaceModel, texture: np.ndarray | None = None) -> tuple[bytes, dict]:
    """The GLB (the face at rest, every part, with ``texture`` on the skin if given) and its key:
    ``{"parts": {primitive part: [mesh vertex of each GL vertex]}, "feature_points": {"labels", "rest"
    (metres)}, "rig": rig_data(face), "deformer": the face's deformer, "lashes": lash_data(face)}``; no lashes
    (None) with a photo texture, which has the person's own, as the renderer draws them.

    The rig is the feature-point deformer's whatever ``face.deformer`` says: the pages pose with it."""
    from mpeg4fa.export.gltf import MM, build_glb, part_sources
    from mpeg4fa.fba.stream import FapStream

    still = FapStream.empty(1)
    still.source_fps = 25.0
    data, _ = build_glb(still, face, animation="vertex", texture=texture, name="head")
    rest = face.mesh.vertices[np.asarray(face.mesh.fp_vertex)] * MM
    key = {"parts": {name: _ints(src) for name, src in part_sources(face).items()},
           "feature_points": {"labels": list(face.mesh.fp_labels), "rest": rest.tolist()},
           "rig": rig_data(face), "deformer": face.deformer,
           "lashes": lash_data(face) if texture is None else None}
    return data, key


def write_fap_head(face: FaceModel, glb_path, key_path, texture: np.ndarray | None = None) -> dict:
    """Write the GLB and its key (JSON) for a static player folder; returns the key."""
    from mpeg4fa.atomic import atomic_outputs

    data, key = fap_head(face, texture)
    with atomic_outputs(glb_path, key_path) as (glb_tmp, key_tmp):
        glb_tmp.write_bytes(data)
        key_tmp.write_text(json.dumps(key), encoding="utf-8")
    return key


__all__ = ["fap_head", "write_fap_head", "rig_data", "lash_data", "RIG_VERSION"]
