"""Feature-point motion -> low-level FAPs: each FAP's own point, along its direction, over its FAPU.

Why these rules: a FAP is defined as the displacement of one feature point along one axis
in units of a distance measured on the neutral face (``spec/faps.csv``: feature point,
direction, FAPU; ``spec/fapu.csv``). So with the head's motion taken out
(:mod:`.pose`) and the FAPU measured on the person's own neutral face
(:func:`mpeg4fa.face.fapu.measure_fapu`, the one home of the FAPU rules), a tracked point's
displacement divided by its FAPU is the value to send, in every face's units.

Three rules come from the receiving head rather than the standard, and are read off it
(:class:`Receiver`, by default the generic head that ``play`` shows): the jaw (FAP 3) carries
the lower lip and the lip corners with it, so the lip FAPs are what is left of a point's drop
after the jaw's share (the fraction of 2.1's drop that point follows on that head); the
eyeball turns (FAPs 23-26, angles) are read from the iris's shift over the radius at which the
head's pupil turns, as a fraction of ES0; and the head's eye corners give a little as its lids close, so what
is read against the corners is read as that head would show it (:attr:`Receiver.corner_carry`).

Points are ``(..., L, 3)`` arrays over :data:`LABELS` (the feature points the landmark model
sees), in MPEG-4 axes: x to the face's left, y up, z out of the face (:func:`to_face_axes`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from mpeg4fa.face.fapu import Fapu, measure_fapu
from mpeg4fa.face import motion
from mpeg4fa.spec import ANGLE_UNIT, FAPS, N_FAPS
from mpeg4fa.tracking.points import SEEN_LABELS

LABELS: tuple[str, ...] = SEEN_LABELS
INDEX = {label: i for i, label in enumerate(LABELS)}

JAW = 3
JAW_POINTS = ("2.1", "2.10", "2.11", "2.12")
"""The chin's points: each drops by its share of the jaw's opening, so together they read it steadier than 2.1."""
JAW_LIP, JAW_LIP_WEIGHT = "2.3", 0.5
"""The lower lip's middle, which the jaw carries too, joins the chin's reading of the jaw with this weight (the chin's
points together weigh 1). Why: the landmark model finds the chin on a soft outline and reads its drop short, the
lip's edge it finds sharply. In tools/track_loop.py (12 s) the jaw's correlation with what was sent rose from
0.80 to 0.91 with the head still and from 0.82 to 0.89 while it turns, and the inner lips' error fell from 20 % to
14 % of their range. The cost, measured on the head's own points: a lower lip dropping on its own (FAP 5 without
the jaw) is read one third as jaw, so the inner lips there give back 0.97 of what was sent instead of 0.98."""
LIDS = (19, 20, 21, 22)
GAZE_YAW = {23: "3.5", 24: "3.6"}
GAZE_PITCH = {25: "3.5", 26: "3.6"}
HEAD = (48, 49, 50)
TRANSLATIONS: tuple[int, ...] = (3, *range(4, 14), 19, 20, 21, 22, *range(31, 39), *range(39, 43), *range(51, 61))
"""Translational FAPs read from their point's displacement: jaw, inner lips, lids, brows, cheeks, outer lips.
Depth FAPs (14, 16, 17, 27, 28) are left out: a camera's depth is too rough for them."""
SENT: tuple[int, ...] = tuple(sorted((*TRANSLATIONS, *GAZE_YAW, *GAZE_PITCH, *HEAD)))
"""Every FAP a tracked stream sends (a fixed set, so the mask never changes and costs no extra intra frame)."""

RIGID_LABELS: tuple[str, ...] = tuple(label for label in LABELS if label in {
    "3.7", "3.8", "3.11", "3.12", "9.3", "9.4", "9.5", "9.6", "9.7", "9.12", "9.13", "9.14", "9.15",
    "10.9", "10.10", "11.1", "11.2", "11.3"})
"""Points no sent FAP moves (eye corners, nose, forehead, face oval at the ears): the head pose is fitted on them.
(The engine's eye corners give a millimetre or so as its lids close, :func:`mpeg4fa.face.lids.lid_corners`; what
that does to the points measured against the corners, :attr:`Receiver.corner_carry` takes out.)"""
RIGID = np.array([INDEX[label] for label in RIGID_LABELS])
_MOVING_GROUPS = ("3", "4")  # eyes, lids and brows move: landmarks near them are not rigid
RIGID_CLEARANCE = 0.15
"""How far (a fraction of the eye distance) a landmark must lie from every eye and brow point to be rigid."""


def rigid_landmarks(landmarks: np.ndarray) -> np.ndarray:
    """Indices of the landmarks no sent FAP moves, read off one face (MPEG-4 axes): above the bottom of the
    nose (the jaw, lips and cheeks move below it) and clear of the eyes and brows. Dozens of landmarks
    over the forehead, temples and nose hold the head's pose steadier than the few rigid feature points."""
    from mpeg4fa.tracking.points import feature_point_array

    landmarks = np.asarray(landmarks, dtype=np.float64)
    points = feature_point_array(landmarks)
    eyes = float(np.linalg.norm(points[INDEX["3.5"]] - points[INDEX["3.6"]]))
    moving = [INDEX[label] for label in LABELS if label.split(".")[0] in _MOVING_GROUPS]
    gap = np.linalg.norm(landmarks[:, None, :2] - points[None, moving, :2], axis=2).min(axis=1)
    return np.flatnonzero((landmarks[:, 1] > points[INDEX["9.15"], 1]) & (gap > RIGID_CLEARANCE * eyes))


EYE_CORNERS = {"l": ("3.7", "3.11"), "r": ("3.8", "3.12")}
ANCHORS: dict[str, tuple[str, ...]] = {
    **{label: EYE_CORNERS["l"] for label in ("3.1", "3.3", "3.5", "4.1", "4.3", "4.5")},
    **{label: EYE_CORNERS["r"] for label in ("3.2", "3.4", "3.6", "4.2", "4.4", "4.6")},
}
"""Points measured against their eye's corners rather than the whole head: lids, irises and brows sit next to
them, so an error in the fitted head turn shifts both alike and cancels (lids: half the error, on rendered
turns of 30 degrees), and the iris's place between the corners is what gaze is."""


def _anchor_matrix() -> np.ndarray:
    """(L, L) matrix that subtracts each anchored point's anchor (mean of its anchor points)."""
    m = np.eye(len(LABELS))
    for label, anchors in ANCHORS.items():
        if label in INDEX and all(a in INDEX for a in anchors):
            for a in anchors:
                m[INDEX[label], INDEX[a]] -= 1.0 / len(anchors)
    return m


def to_face_axes(pixels: np.ndarray) -> np.ndarray:
    """Image points (x right, y down, z toward the camera negative, pixels) in MPEG-4 axes (x to the face's
    left, which the camera sees on the image's right; y up; z toward the camera)."""
    p = np.asarray(pixels, dtype=np.float64)
    return p * np.array([1.0, -1.0, -1.0])


@dataclass(frozen=True)
class Receiver:
    """What the head that will play the FAPs does beyond the standard's one-point rules."""

    jaw_carry: np.ndarray
    """(L,) fraction of 2.1's vertical drop each of :data:`LABELS` follows when the jaw opens (FAP 3)."""
    eye_radius: float
    """Radius of the pupil's turn about the eyeball's centre, as a fraction of ES0."""
    corner_carry: np.ndarray = field(default_factory=lambda: np.zeros(len(LIDS)))
    """(4,) per lid FAP of :data:`LIDS`: how far its eye's corners (their mean) move up per unit its lid point moves up,
    as the head's corners give a little when its lids close (:func:`mpeg4fa.face.lids.lid_corners`). Measured against
    those corners, a blink at 1000 read 848 on the generic head, with 152 on the lower lids. Read with it, a face
    whose corners stay put sends a full blink as about 1.2 x on the upper lid and -0.2 x on the lower: what the head
    needs to show that blink against its own corners. A head whose corners would carry more than
    :data:`MOST_CORNER_CARRY` of its lids (the solve's divisor 1 - ku - kl near 0) is read as if they stayed."""


@lru_cache(maxsize=4)
def receiver(face=None) -> Receiver:
    """The jaw's carry, the eye's radius and the eye corners' carry of ``face`` (default: the generic head), measured
    by posing it."""
    from mpeg4fa.face import FaceModel

    face = face if face is not None else FaceModel.default()
    labels = list(face.mesh.fp_labels)
    rest = face.deform({}).feature_points
    jaw = face.deform({JAW: 512}).feature_points - rest
    drop = jaw[labels.index("2.1"), 1]
    carry = np.array([jaw[labels.index(label), 1] / drop if label in labels and drop else 0.0 for label in LABELS])
    angle = 0.2
    turned = face.deform({23: angle / ANGLE_UNIT}).feature_points - rest
    shift = float(turned[labels.index("3.5"), 0])
    corners = []
    for fap in LIDS:
        lid = face.deform({fap: 512}).feature_points - rest
        point = FAPS[fap - 1].feature_point[0]
        eye = [labels.index(a) for a in ANCHORS[point] if a in labels]
        rise = lid[labels.index(point), 1] if point in labels else 0.0
        corners.append(float(np.mean(lid[eye, 1])) / rise if eye and rise else 0.0)
    return Receiver(jaw_carry=carry, eye_radius=abs(shift) / np.sin(angle) / face.fapu.ES0,
                    corner_carry=np.array(corners))


@dataclass(frozen=True)
class Neutral:
    """The neutral face in MPEG-4 axes, the FAPU measured on it, and the head that will play the FAPs."""

    points: np.ndarray  # (L, 3), pixels
    fapu: Fapu

    @classmethod
    def from_points(cls, points: np.ndarray) -> "Neutral":
        """A neutral from its feature points (MPEG-4 axes); FaceError when they give no FAPU (out of order)."""
        points = np.asarray(points, dtype=np.float64)
        return cls(points=points, fapu=measure_fapu(dict(zip(LABELS, points))))


def _table() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per translational FAP: column (FAP - 1), point index, unit direction, FAPU symbol."""
    cols, points, dirs, units = [], [], [], []
    for fap in TRANSLATIONS:
        record = FAPS[fap - 1]
        cols.append(fap - 1)
        points.append(INDEX[record.feature_point[0]])
        dirs.append(motion.direction(fap))
        units.append(record.fapu)
    return np.array(cols), np.array(points), np.array(dirs), np.array(units)


_COLS, _POINTS, _DIRS, _UNITS = _table()
_ANCHOR = _anchor_matrix()


MOST_CORNER_CARRY = 0.6
"""Most ``ku + kl`` (:attr:`Receiver.corner_carry` of one eye's two lids) that is taken out (the generic head's: 0.35);
past it the solve (divided by ``1 - ku - kl``) would amplify the lids' landmark noise."""


def _add_back_the_corners(d: np.ndarray, corner_carry: np.ndarray) -> None:
    """``d`` (points less their anchors, ``(n, L, 3)``) as if each eye's corners had stayed put while its lids moved
    (:attr:`Receiver.corner_carry`): per eye, its lid points' rises solved from what they read against the corners
    (the corners rise ``ku`` x the upper's plus ``kl`` x the lower's), and the corners' rise added back to every point
    measured against them."""
    lids = dict(zip(LIDS, corner_carry))
    for upper, lower in ((19, 21), (20, 22)):
        ku, kl = lids[upper], lids[lower]
        if not (ku or kl) or ku + kl > MOST_CORNER_CARRY:
            continue
        u, low = (INDEX[FAPS[f - 1].feature_point[0]] for f in (upper, lower))
        rise = (ku * d[:, u, 1] + kl * d[:, low, 1]) / (1.0 - ku - kl)  # = ku x the upper's rise + kl x the lower's
        for label, anchors in ANCHORS.items():
            if anchors == ANCHORS[FAPS[upper - 1].feature_point[0]]:
                d[:, INDEX[label], 1] += rise


def fap_values(local: np.ndarray, neutral: Neutral, angles: np.ndarray, geometry: Receiver) -> np.ndarray:
    """``(n, 68)`` FAP values (float, FAPU or AU; unsent FAPs 0) from points with the head's motion taken out.

    ``local``: ``(n, L, 3)`` feature points in the neutral's coordinates (MPEG-4 axes); ``angles``:
    ``(n, 3)`` head pitch, yaw, roll in radians (:mod:`.pose`). NaN points give NaN values."""
    local = np.asarray(local, dtype=np.float64)
    n = local.shape[0]
    d = np.einsum("kl,nlc->nkc", _ANCHOR, local - neutral.points[None])
    carry = geometry.jaw_carry.copy()
    carry[INDEX["2.1"]] = 1.0  # 2.1 is the jaw's own point
    chin = [INDEX[label] for label in JAW_POINTS if label in INDEX and carry[INDEX[label]] > 0.5]
    jaw_drop = np.mean(d[:, chin, 1] / carry[chin], axis=1)  # 2.1's drop, read off the whole chin
    lip = INDEX[JAW_LIP]
    if carry[lip] > 0.5:  # and off the lower lip the jaw carries (a head whose jaw leaves its lip: the chin alone)
        jaw_drop = (jaw_drop + JAW_LIP_WEIGHT * d[:, lip, 1] / carry[lip]) / (1.0 + JAW_LIP_WEIGHT)
    d[:, :, 1] -= carry[None, :] * jaw_drop[:, None]
    d[:, INDEX["2.1"], 1] = jaw_drop  # the jaw's own point is the jaw
    _add_back_the_corners(d, geometry.corner_carry)
    unit = np.array([neutral.fapu.unit(u) for u in _UNITS])
    out = np.zeros((n, N_FAPS))
    out[:, _COLS] = np.einsum("nkc,kc->nk", d[:, _POINTS], _DIRS) / unit
    radius = geometry.eye_radius * neutral.fapu.ES0
    for fap, label in GAZE_YAW.items():  # positive turns either eye toward the face's left (+x)
        out[:, fap - 1] = np.arcsin(np.clip(d[:, INDEX[label], 0] / radius, -1, 1)) / ANGLE_UNIT
    for fap, label in GAZE_PITCH.items():  # positive looks down (-y)
        out[:, fap - 1] = np.arcsin(np.clip(-d[:, INDEX[label], 1] / radius, -1, 1)) / ANGLE_UNIT
    for fap, column in zip(HEAD, range(3)):
        out[:, fap - 1] = np.asarray(angles, dtype=np.float64)[:, column] / ANGLE_UNIT
    return out
