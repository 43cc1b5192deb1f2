"""No creases or folds in what a talking head does every second (issue 29 item 3): joy at its profile's 63,
its cheek lifts, a blink at every stage and the lower lids of a smile, on the feature-point and ARKit
deformers (:mod:`mpeg4fa.face.creases`: no folded triangle, no fold line; the strain against its floor
where it is reached).

Measured on the generic head before the fixes (folded / fold lines, the same on both deformers but where
named): joy at 63 6 / 14 (ARKit 22 / 30), its cheeks 41/42 at 200 0 / 2 (ARKit 16 / 18), the lower lids at
260 6 / 12 and at 300 8 / 14, a blink at 400 4 / 2, 600 20 / 10, 1000 42 / 32. Fixed by evening out the lid
sheets' angle shares at the eye corners (:mod:`mpeg4fa.face.lid_folds`), the cheek points' skin weights
(:data:`mpeg4fa.face.rig.RELIEVED`) and ARKit's sculpted cheekSquint (:data:`.deformers.arkit.RELIEVED`),
all by :func:`mpeg4fa.face.fold_relief.even_out`, with the eye corners and the other margin's ends riding the lids
(a blink at 400-700, the lower lids at 300-520 and a blink at 500 over them then fold nothing); where ARKit's
sculpt still nears a fold (joy 2 folded, disgust 4 fold lines), the skin around takes the feature-point field
(:data:`mpeg4fa.face.deformers.arkit.FALLBACK_MM`).
What is not met is marked with its measured figure.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import face_under
from mpeg4fa.face import creases, lids, quality
from mpeg4fa.face.lid_folds import CORNER_FREE_MM
from mpeg4fa.face.regions import edge_graph
from mpeg4fa.spec.profiles import expression_blend

DEFORMERS = ("fap", "arkit")
BLINK_STAGES = tuple(range(100, 1001, 100))  # FAP 19/20 (IRISD) up to a blink's peak (tools/track_loop.BLINK_PEAK)
LOWER_STAGES = (100, 200, 260, 300, 400, 520)  # FAP 21/22: joy at 63 asks 260, at 63 x 2 520
CORNER = ("where the margin, held to its closure so that the eye shuts, climbs the corner more steeply "
          "than the lid can turn past it, the corner giving less")
NOT_YET = {
    **{(d, f"blink {s}"): f"{fig} at the eye corners ({CORNER})" for d in DEFORMERS for s, fig in (
        (800, "0 folded / 2 fold lines, was 8 / 10 with the corners and the other margin held, 32 / 28 before the "
              "evening out"),
        (900, "2 / 4, was 8 / 14, 34 / 30"), (1000, "4 / 4, was 14 / 14, 42 / 32"))},
    **{(d, "blink 1000 over lower 260"): "4 / 4 at the eye corners since the upper lid stops on the lower, was "
                                         "10 / 10 with the corners held, 18 / 18, 48 / 44 at first" for d in DEFORMERS},
}


def _values(**faps: float) -> np.ndarray:
    v = np.zeros(68)
    for key, value in faps.items():
        v[int(key[1:]) - 1] = value
    return v


def expression(name: str) -> np.ndarray:
    """An expression at its profile's intensity, alone (the profile's own 63)."""
    v = np.asarray(expression_blend(name, 63, name, 0), float)[:68].copy()
    v[:2] = 0
    return v


def ordinary_poses() -> dict[str, np.ndarray]:
    # the other five at 63 too: disgust drew 4 fold lines on ARKit before its fallback (arkit.FALLBACK_MM)
    poses = {f"{name} 63": expression(name) for name in ("joy", "sadness", "anger", "fear", "disgust", "surprise")}
    poses["joy cheeks 200"] = _values(f41=200, f42=200)
    poses.update({f"blink {s}": _values(f19=s, f20=s) for s in BLINK_STAGES})
    poses.update({f"lower {s}": _values(f21=s, f22=s) for s in LOWER_STAGES})
    poses.update({f"blink {u} over lower {s}": _values(f19=u, f20=u, f21=s, f22=s)
                  for u, s in ((500, 260), (1000, 260))})
    return poses


POSES = ordinary_poses()


@pytest.fixture(scope="module")
def graph(generic_face):
    return quality.skin_graph(generic_face.mesh)


def _cases():
    for deformer in DEFORMERS:
        for name in POSES:
            why = NOT_YET.get((deformer, name))
            marks = [pytest.mark.xfail(reason=why, strict=False)] if why else []
            yield pytest.param(deformer, name, marks=marks, id=f"{deformer}-{name.replace(' ', '_')}")


@pytest.mark.parametrize("deformer,name", list(_cases()))
def test_ordinary_pose_folds_nothing(request, graph, deformer, name):
    face = face_under(request, "generic", deformer)
    m = creases.measure_pose(face, POSES[name], graph)
    assert m.folded == 0 and m.flipped == 0, f"{name}: {m}"


@pytest.mark.parametrize("deformer,name", [
    ("fap", "joy 63"), ("arkit", "joy 63"), ("fap", "joy cheeks 200"), ("arkit", "joy cheeks 200")])
def test_joy_keeps_to_the_floor(request, graph, deformer, name):
    """Joy at 63 within 2 x its floor (1.47 on fap, 1.59 on ARKit), its cheek lifts too (1.86 on fap, was 1.94;
    1.78 on ARKit, was 2.09 beside the outer eye corner 3.7 before the skin there took the feature-point field
    where the sculpted cheekSquint neared a fold, arkit.FALLBACK_MM)."""
    face = face_under(request, "generic", deformer)
    m = creases.measure_pose(face, POSES[name], graph)
    assert m.ratio <= creases.FLOOR_FACTOR, f"{name}: {m}"


@pytest.mark.xfail(reason="the lids' strain is 2.3-3.4 x its floor at every value (3.31-3.38 at a blink of 100-1000, "
                          "3.21-3.25 before the upper lids' front edges closed onto the lower ones; 2.28 for the lower "
                          "lids, 3.61 before the corners rode the lids; was 3.36 / 4.86): the margin turns to the "
                          "other lid within 0.6 mm of a corner that gives less than it",
                   strict=False)
@pytest.mark.parametrize("name", ["blink 1000", "lower 260"])
def test_lids_keep_to_the_floor(generic_face, graph, name):
    assert creases.measure_pose(generic_face, POSES[name], graph).ratio <= creases.FLOOR_FACTOR


def test_evened_lids_still_shut_the_eye(generic_face):
    """The evening out leaves each lid point its whole turn (value x IRISD), moves no other feature point but the
    eye's corners (which give under 2 mm even when the lid shuts alone, :mod:`mpeg4fa.face.lid_folds`), and keeps
    every margin vertex further than CORNER_FREE_MM from a corner closing onto the other lid: at the closing value
    each sits at or past the other margin's height at its x."""
    face = generic_face
    mesh, rest = face.mesh, face.mesh.vertices
    graph = edge_graph(rest, mesh.triangles["skin"])
    anchors = {int(v) for label, v in zip(mesh.fp_labels, mesh.fp_vertex) if label not in lids.PASSIVE_POINTS}
    for fap, (_eye, _joint, point, opposite, lateral, medial, side) in lids.LIDS.items():
        sheet = face.rig.lids[fap]
        assert sheet.ratios[list(sheet.rows).index(sheet.point)] == 1.0
        ends = [int(mesh.fp_vertex[mesh.fp_index(label)]) for label in lids.lid_corners(fap)]
        assert not (set(sheet.rows.tolist()) & anchors) - {sheet.point, *ends}
        own, other = (lids._margin(graph, mesh, lateral, label, medial) for label in (point, opposite))
        closing = abs(mesh.fp(point)[1] - mesh.fp(opposite)[1]) / face.fapu.unit("IRISD")
        posed = face.unlimited().deform({fap: closing}).vertices
        given = np.linalg.norm(posed[ends] - rest[ends], axis=1)
        assert given.max() < 2.0, f"FAP {fap}: a corner gives {given.max():.2f} mm"
        corners = rest[ends]
        far = own[np.linalg.norm(rest[own][:, None] - corners[None], axis=2).min(axis=1) > CORNER_FREE_MM]
        # the other margin's rest height: its ends give with this lid (up to 0.6 mm below where the shut margin stops,
        # 1-2 mm from a corner), and the front edges, which close onto each other, cover that (test_lid_pixels)
        target = lids.height_at(other, rest, rest[far, 0])
        gap = (posed[far, 1] - target) if side == "upper" else (target - posed[far, 1])
        assert gap.max() < 0.05, f"FAP {fap}: a margin vertex stops {gap.max():.2f} mm short of the other lid"
