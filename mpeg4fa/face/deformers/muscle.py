"""The muscle deformer: FAPs contract Waters' linear muscles, the skin follows, feature points stay exact.

1. The feature-point deformer's targets: every skin feature point's FAP-driven motion
   in the jaw's frame (``rig.translate @ values``; 0 for the points no FAP drives).
2. The contractions: the 18 solved muscles (:mod:`mpeg4fa.face.muscles`, ``data/muscles.csv``:
   frontalis (medial, middle and lateral bellies), corrugator, levator labii superioris,
   zygomatic major, risorius, depressor labii inferioris, mentalis, each side) are fitted to
   those targets by non-negative least squares (muscles only pull) with a small ridge
   (:data:`RIDGE`), over all the skin's anchored feature points at once; only the muscles
   that move a point the frame drives take part, and a paired muscle serves its own side
   and the midline only (a left FAP contracts no right muscle). The levator
   palpebrae's contraction is its upper lid point's rise (FAP 19/20), and its action is the
   lid sheet turning over the eyeball as in the feature-point deformer (:mod:`.lids`): its
   Waters field is built (``basis``) but not added to the skin, so that a lid FAP moves its
   lid sheet only and no lid vertex leaves its distance from the eye centre
   (``tests/face/test_lids.py``).
3. The residual correction: what the muscles leave at the feature points (what they
   cannot reach, and their motion of points that should stay put) is spread by the
   feature-point deformer's own smooth skin weights (:func:`.rig.skin_weights`), so every
   feature point lands exactly where the FAPU semantics put it. The skin is then
   ``rest + muscles + weights @ (targets - muscles at the points)``, precomputed as the
   feature-point pose plus ``G @ K`` with ``G = B - W B_fp`` (linear in the contractions),
   faded out across the midline for a paired muscle (0 at every feature point either way).

Jaw, lids, eyes, tongue and head come from the feature-point deformer
(:func:`.feature_points.pose_in_head_frame`, :func:`.apply_lids`, :func:`.apply_head_rotation`);
the muscle field rides on the jaw (it is added before the jaw's rotation).

What the muscles alone reach (:func:`reach_table`: each FAP alone at +-200 on the
generic head, before the correction; ``alone`` is the relative error at the FAP's own
point when the muscles are fitted to that point only, ``along`` the share of the motion
they then deliver along the FAP's direction). No FAP is reached within 1 % by the
muscles alone: a linear muscle pulls along a chord toward bone, so it always adds motion
the FAP does not ask for, and in the deformer's own fit the neighbouring points that must
stay put hold it back further. In part (``alone`` / ``along``):

* brows raised (31-36 +, frontalis, up *and back*): 29-34 % / 88-92 %;
* upper lip raised (4, 8/9, 51, 55/56 -, levator labii superioris): 36-52 % / 73-87 %;
* lower lip lowered (5, 10/11, 52, 57/58 -, depressor labii inferioris): 43-55 % / 70-81 %;
* corners raised and stretched (6/7, 12/13, 53/54, 59/60 +, zygomatic major, risorius,
  which pull as much back into the cheek as up and out): 62-66 % / 56-61 %;
* inner brows squeezed (37/38 +, corrugator, which also lowers them): 62 % / 62 %;
* chin and lower lip raised (18 +, mentalis; 10/11, 57/58 +): 71-78 % / 40-50 %.

Not at all (``alone`` over 84 %): lowering the upper lip or raising the lower lip at the
midline (4, 5, 8/9 +: orbicularis oris, a sphincter, is not in the set), pushing or pulling
the lips (16/17), narrowing or lowering the corners (6/7, 53/54 -; 12/13, 59/60 -: depressor
anguli oris is not in the set), brows straight down (31-36 -), brows apart (37/38 -), the
cheeks (39-42), the nose (61-64) and the ears (65-68). Those motions are realised by the
residual correction alone, that is as the feature-point deformer moves them. In the
expressions, where FAPs come together, the muscles carry most of the brows and corners.
``python -m mpeg4fa.face.deformers.muscle`` prints the table.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

from mpeg4fa.face import motion
from mpeg4fa.face.couplings import PASSIVE_POINTS
from mpeg4fa.face.deformers.feature_points import FoldGuard, apply_head_rotation, apply_lids, pose_in_head_frame, skin_guard
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.muscles import CROSS_ES, Muscle, muscle_basis, place_muscles
from mpeg4fa.face.regions import smooth_down
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.rig import Rig, skin_weights
from mpeg4fa.spec import FAP_BY_NAME, FAPS, N_FAPS

RIDGE = 1e-3  # squared weight of the contractions (mm) against the feature point residuals (mm)
SERVES_MM = 0.05  # a muscle serves a feature point it moves by more than this per mm of contraction
MIDLINE_ES = 0.02  # feature points within this (in ES0) of the midline belong to both sides
_JAW_OPEN = next(f for f, k in motion.JAW.items() if k == "open")
_UPPER_LID = {"l": FAP_BY_NAME["close_t_l_eyelid"].number, "r": FAP_BY_NAME["close_t_r_eyelid"].number}


@dataclass(frozen=True)
class MuscleRig:
    """Everything a frame needs, precomputed for one neutral face."""

    muscles: tuple[Muscle, ...]
    basis: np.ndarray  # (skin vertices, 3, M): displacement per mm of contraction
    solved: np.ndarray  # indices of the muscles fitted to the targets
    lid_driven: tuple[tuple[int, int], ...]  # (muscle index, upper lid FAP)
    anchors: np.ndarray  # feature point indices of the skin points the fit and the correction use
    anchors_local: np.ndarray  # their vertices, local to the skin part
    fit: np.ndarray  # (3 * anchors + solved, solved): the points' motion per contraction, and the ridge
    serves: np.ndarray  # (solved, anchors) 1/0: the muscle moves that point (more than SERVES_MM per mm)
    target_rows: np.ndarray  # rows of (rig.translate @ v) that are the anchors' targets (3 per anchor)
    translate: np.ndarray  # rig.translate[target_rows]: FAP values -> the anchors' targets
    rows: np.ndarray  # global vertex indices the muscles move (after correction)
    field: np.ndarray  # (3 * rows, M): G = B - W B_fp on those rows
    jaw_local: np.ndarray  # positions in ``rows`` of vertices the jaw turns
    jaw_weight: np.ndarray

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(m.name for m in self.muscles)


def build_muscle_rig(mesh: HeadMesh, rig: Rig) -> MuscleRig:
    """Place the muscles on this face, build their basis, the fit and the corrected field."""
    muscles = tuple(place_muscles(mesh, rig.fapu))
    basis = muscle_basis(mesh, list(muscles), rig.fapu)
    skin = mesh.part("skin")
    labels = mesh.fp_labels
    fp_v = mesh.fp_vertex
    anchors = [i for i in range(len(labels)) if skin.start <= fp_v[i] < skin.stop and labels[i] not in PASSIVE_POINTS]
    # one anchor per distinct vertex (11.5 shares 11.4's)
    _, first = np.unique(fp_v[anchors], return_index=True)
    anchors = np.array(sorted(np.array(anchors)[first]))
    weights = skin_weights(mesh, list(anchors), list(anchors))[skin][:, anchors].toarray()  # (skin, anchors)
    local_fp = fp_v[anchors] - skin.start
    n_skin, m = basis.shape[0], basis.shape[2]
    b_fp = basis[local_fp]  # (anchors, 3, M)
    field = basis - np.einsum("va,axm->vxm", weights, b_fp)
    field[:, :, [j for j, mu in enumerate(muscles) if mu.spec.driven_by == "lid"]] = 0.0  # the lid sheets turn
    field[local_fp] = 0.0  # exactly (the weights are 1 at their own point, 0 at the others')
    # the correction of a midline point (11.1, 9.12...) spreads over both sides: a paired muscle's
    # field, correction included, ends where its basis does (CROSS_ES across the midline); it stays
    # 0 at every feature point, so the points stay exact
    x_skin = mesh.lateral()[skin]
    reach = CROSS_ES * rig.fapu.ES0
    for j, mu in enumerate(muscles):
        if mu.side in ("l", "r"):
            across = -(1.0 if mu.side == "l" else -1.0) * x_skin
            field[:, :, j] *= smooth_down((across - reach / 2) / (reach / 2))[:, None]
    moved = np.flatnonzero(np.abs(field).reshape(n_skin, -1).max(axis=1) > 1e-12)

    solved = np.array([j for j, mu in enumerate(muscles) if mu.spec.driven_by == "solve"])
    lid_driven = tuple((j, _UPPER_LID[mu.side]) for j, mu in enumerate(muscles) if mu.spec.driven_by == "lid")
    a = b_fp[:, :, solved].reshape(-1, len(solved))
    serves = (np.linalg.norm(b_fp[:, :, solved], axis=1) > SERVES_MM).T.astype(np.float64)
    # a paired muscle serves its own side and the midline only (a left FAP contracts no right muscle)
    x = mesh.lateral()[fp_v[anchors]] / rig.fapu.ES0
    for row, j in enumerate(solved):
        side = {"l": 1.0, "r": -1.0}.get(muscles[j].side)
        if side is not None:
            serves[row] *= side * x > -MIDLINE_ES
    fit = np.vstack([a, np.sqrt(RIDGE) * np.eye(len(solved))])
    target_rows = (3 * anchors[:, None] + np.arange(3)).ravel()

    jaw_rows, jaw_w = rig.jaw_rows
    global_rows = moved + skin.start
    where = {int(v): k for k, v in enumerate(global_rows)}
    pairs = [(where[int(v)], w) for v, w in zip(jaw_rows, jaw_w) if int(v) in where]
    jaw_local = np.array([p for p, _ in pairs], dtype=np.intp)
    jaw_weight = np.array([w for _, w in pairs], dtype=np.float64)
    return MuscleRig(muscles=muscles, basis=basis, solved=solved, lid_driven=lid_driven, anchors=anchors,
                     anchors_local=local_fp,
                     fit=np.asfortranarray(fit), serves=serves, target_rows=target_rows,
                     translate=np.ascontiguousarray(rig.translate[target_rows]), rows=global_rows,
                     field=np.ascontiguousarray(field[moved].reshape(-1, m)), jaw_local=jaw_local,
                     jaw_weight=jaw_weight)


def contractions(rig: Rig, mrig: MuscleRig, values: np.ndarray) -> np.ndarray:
    """Every muscle's contraction (mm) for one frame of FAPs."""
    v = np.asarray(values, dtype=np.float64)
    k = np.zeros(len(mrig.muscles))
    targets = mrig.translate @ v
    if targets.any():
        # only muscles that move a point this frame drives take part (a left FAP contracts no right muscle)
        driven = np.abs(targets.reshape(-1, 3)).sum(axis=1) > 0
        active = np.flatnonzero(mrig.serves @ driven)
        if len(active) == len(mrig.solved):
            k[mrig.solved] = nnls(mrig.fit, np.concatenate([targets, np.zeros(len(active))]))[0]
        elif len(active):
            n = len(targets)
            a = np.vstack([mrig.fit[:n, active], mrig.fit[n + active][:, active]])
            k[mrig.solved[active]] = nnls(a, np.concatenate([targets, np.zeros(len(active))]))[0]
    iris = rig.fapu.unit("IRISD")
    for j, fap in mrig.lid_driven:
        k[j] = motion.direction(fap)[1] * v[fap - 1] * iris  # the lid point's rise (mm)
    return k


def muscle_motion(mrig: MuscleRig, k: np.ndarray) -> np.ndarray:
    """``(anchors, 3)``: what the muscles alone do to the anchored feature points (before correction)."""
    b_fp = mrig.basis[mrig.anchors_local].reshape(-1, len(mrig.muscles))
    return (b_fp @ k).reshape(-1, 3)


def deform_muscle(rig: Rig, mrig: MuscleRig, values: np.ndarray, guard: FoldGuard | None = None) -> Pose:
    """Pose one frame: muscles shape the skin, feature points exactly where the FAPs put them; ``guard``
    is the feature-point deformer's fold guard for the skin under the muscles."""
    v = np.asarray(values, dtype=np.float64)
    p, pupils = pose_in_head_frame(rig, v, lids=False, guard=guard)
    k = contractions(rig, mrig, v)
    if k.any():
        delta = (mrig.field @ k).reshape(-1, 3)
        if v[_JAW_OPEN - 1] and len(mrig.jaw_local):  # the field rides on the jaw: turn it with the jaw
            pivot = rig.rest[rig.joints["mouth"]]
            chin = rig.rest[rig.fp_vertex[rig.chin_fp]]
            angle = motion.arc_angle((chin - pivot)[1:], v[_JAW_OPEN - 1] * rig.fapu.unit("MNS"))
            step = motion.rotation_matrix(0, angle) - np.eye(3)
            delta[mrig.jaw_local] += mrig.jaw_weight[:, None] * (delta[mrig.jaw_local] @ step.T)
        p[mrig.rows] += delta
    apply_lids(rig, p, v)
    apply_head_rotation(rig, p, v)
    return Pose(vertices=p, parts=rig.parts, pupil_diameter=pupils, fp_vertex=rig.fp_vertex)


@dataclass(frozen=True)
class MuscleDeformer:
    """The muscle deformer set up for one face (its muscle rig kept for inspection)."""

    rig: Rig
    muscle_rig: MuscleRig
    guard: FoldGuard | None = None

    def __call__(self, values: np.ndarray) -> Pose:
        return deform_muscle(self.rig, self.muscle_rig, values, self.guard)

    def contractions(self, values: np.ndarray) -> dict[str, float]:
        """Muscle name -> contraction (mm) for one frame."""
        return dict(zip(self.muscle_rig.names, contractions(self.rig, self.muscle_rig, values).tolist()))


def build(mesh: HeadMesh, rig: Rig) -> MuscleDeformer:
    return MuscleDeformer(rig, build_muscle_rig(mesh, rig), skin_guard(mesh, rig))


@dataclass(frozen=True)
class Reach:
    """How much of one FAP's feature point motion the muscles alone deliver (before correction)."""

    fap: int
    value: float
    own: float  # |muscle motion - target| / |target| at the FAP's own point(s) (worst), the deformer's fit
    fit: float  # |muscle motion - targets| / |targets| over every anchored skin point, the deformer's fit
    alone: float  # ``own`` when the muscles are fitted to the FAP's own point(s) only (the others free)
    along: float  # in that fit, the share of the FAP's motion delivered along its direction (1 = all)

    @property
    def reached(self) -> bool:
        return self.own < 0.01


def reach_table(mesh: HeadMesh, rig: Rig, mrig: MuscleRig, value: float = 200.0) -> list[Reach]:
    """Each skin-translating FAP alone at +value and (unless unidirectional) -value."""
    row_of = {int(mesh.fp_vertex[a]): k for k, a in enumerate(mrig.anchors)}
    out = []
    for record in FAPS[2:]:
        fap = record.number
        if motion.kind(fap) != "translate":
            continue
        own_rows = [row_of[int(mesh.fp_vertex[mesh.fp_index(label)])] for label in record.feature_point
                    if int(mesh.fp_vertex[mesh.fp_index(label)]) in row_of]
        if not own_rows:  # the tongue
            continue
        for sign in ((1.0,) if record.unidirectional else (1.0, -1.0)):
            v = np.zeros(N_FAPS)
            v[fap - 1] = sign * value
            targets = (mrig.translate @ v).reshape(-1, 3)
            moved = muscle_motion(mrig, contractions(rig, mrig, v)).reshape(-1, 3)
            own = max(float(np.linalg.norm(moved[r] - targets[r]) / np.linalg.norm(targets[r])) for r in own_rows)
            fit = float(np.linalg.norm(moved - targets) / np.linalg.norm(targets))
            rows = (3 * np.array(own_rows)[:, None] + np.arange(3)).ravel()
            a = mrig.fit[:3 * len(mrig.anchors)][rows]
            k_alone = nnls(a, targets.ravel()[rows])[0] if len(rows) else np.zeros(a.shape[1])
            t_own = targets.ravel()[rows]
            m_own = a @ k_alone
            alone = float(np.linalg.norm(m_own - t_own) / np.linalg.norm(t_own))
            along = float(m_own @ t_own / (t_own @ t_own))
            out.append(Reach(fap, sign * value, own, fit, alone, along))
    return out


def _main() -> None:  # pragma: no cover - a report for people
    from mpeg4fa.face.model import FaceModel

    face = FaceModel.default().with_deformer("muscle")
    for r in reach_table(face.mesh, face.rig, face.posing.muscle_rig):
        name = FAPS[r.fap - 1].name
        print(f"{r.fap:3d} {name:24s} {r.value:+5.0f}  own {r.own:6.1%}  fit {r.fit:6.1%}  alone {r.alone:6.1%}"
              f"  along {r.along:6.1%}{'  reached alone' if r.alone < 0.01 else ''}")


if __name__ == "__main__":  # pragma: no cover
    _main()
