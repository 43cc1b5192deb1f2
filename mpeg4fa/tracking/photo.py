"""One photo of a face -> its feature points in 3D -> an FDP that carries the photo as its texture.

>>> made = fdp_from_photo("me.jpg")                  # or an (H, W, 3) uint8 array
>>> save_fdp(made.fdp, "me.fdp")
>>> face = made.calibrated()                          # the generic head fitted to it (dffd, rbf, elastic)

Steps: the landmark model finds the face (:func:`~.landmarks.find_landmarks`); the table of
``spec/landmark_points.csv`` turns landmarks into the feature points a photo shows
(:func:`~.points.feature_points`); their depth is the landmark model's z, in the photo's own
pixel scale. The points are then turned into the generic head's frame (mm, x toward the face's
left, y up, z out) by the similarity (scale, rotation, shift: :func:`mpeg4fa.face.calibrate.similarity_fit`)
that best lays them on the head's own points, so a face turned or tilted in the photo gives an
upright, frontal FDP. Points a photo cannot show (tongue, teeth, ears, skull) are not sent: the
receiver's head keeps its own, carried along by the calibration. The FDP is the neutral face (the facts file's
definition): a photo's open or smiling lips are closed and levelled and a shut eye opened, in the points only, and
the inner lip midpoints sit where the receiving head has its own along the contour. The photo goes into the FDP as
its texture with every point's texture coordinate (FDP case 3, as ``encode --front`` does), so
any receiver paints the head with it (:mod:`mpeg4fa.render.fdp_texture`).
"""
from __future__ import annotations

import io
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

from mpeg4fa.fdp.build import fdp_from_front
from mpeg4fa.fdp.model import LABEL_INDEX as _LABEL_ORDER, Fdp, TextureImage
from mpeg4fa.tracking.landmarks import Landmarks, find_landmarks
from mpeg4fa.tracking.points import feature_points

__all__ = ["PhotoFdp", "fdp_from_photo", "not_neutral", "photo_points", "read_photo"]

PhotoSource = str | os.PathLike | np.ndarray


@dataclass(frozen=True, eq=False)
class PhotoFdp:
    """An FDP made from a photo, with what it was made from (for previews and checks)."""

    fdp: Fdp
    image: np.ndarray
    """The photo, (H, W, 3) uint8 RGB."""
    landmarks: Landmarks
    pixels: dict[str, np.ndarray]
    """The seen feature points on the photo, (x, y) pixels (x right, y down)."""
    points: dict[str, np.ndarray]
    """The same points in 3D in the generic head's frame (mm): what the FDP carries."""
    scale: float
    """Head millimetres per photo pixel."""
    side: tuple[str, str, int] | None = None
    """With a side photo: its name, the side of the face it shows, and how many points it refined."""
    notes: tuple[str, ...] = ()
    """What of the photo's face was not neutral and was made so in the FDP (:func:`not_neutral`), one line each."""
    _faces: dict = field(default_factory=dict, repr=False)

    def calibrated(self, method: str = "dffd"):
        """The generic head calibrated to the FDP with ``method`` (dffd, rbf or elastic); kept once made."""
        if method not in self._faces:
            from mpeg4fa.face import FaceModel
            self._faces[method] = FaceModel.default().calibrate(self.fdp, method=method)
        return self._faces[method]


def read_photo(photo: PhotoSource, where: str | None = None) -> tuple[np.ndarray, str]:
    """The photo as (H, W, 3) uint8 RGB and the name its errors carry."""
    if isinstance(photo, np.ndarray):
        return photo, where or "photo"
    from mpeg4fa.render.images import read_image
    name = where or os.fsdecode(photo)
    return read_image(photo, "photo", name), name


def photo_points(landmarks: Landmarks, head_points: Mapping[str, np.ndarray] | None = None, *,
                 given: Mapping[str, Sequence[float]] | None = None
                 ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], float]:
    """(pixels, points, scale): the feature points on the photo and in 3D in the head's frame (mm per pixel).

    ``head_points`` (label -> the generic head's point, mm) default to the generic head's own; the
    photo's points (x right, -y, -z: up and out of the face) are laid on them by the least-squares
    similarity, which takes the photo's pose and scale out. ``given`` pixel positions (a user's
    annotation) win over the found ones; a given point the model does not see takes its depth from
    the head's point, brought into the photo by the same similarity.
    """
    return _photo_points(landmarks, head_points, given=given)[:3]


def _photo_points(landmarks: Landmarks, head_points: Mapping[str, np.ndarray] | None = None, *,
                  given: Mapping[str, Sequence[float]] | None = None
                  ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], float, list[str]]:
    """:func:`photo_points`, and the lines of :func:`not_neutral` on the points as found."""
    from mpeg4fa.face.calibrate import similarity_fit

    head = dict(head_points) if head_points is not None else _generic_points()
    found = feature_points(landmarks)
    photo3 = {label: np.array([p[0], -p[1], -p[2]]) for label, p in found.items()}
    shared = [label for label in photo3 if label in head]
    scale, rot, shift = similarity_fit(np.array([photo3[label] for label in shared]),
                                       np.array([head[label] for label in shared], dtype=np.float64))
    pixels = {label: p[:2].copy() for label, p in found.items()}
    for label, xy in (given or {}).items():
        x, y = (float(v) for v in xy)
        if label in photo3:
            z = photo3[label][2]
        elif label in head:   # the head's point in the photo's frame: its depth there
            z = (rot.T @ (np.asarray(head[label], float) - shift) / scale)[2]
        else:
            continue
        pixels[label] = np.array([x, y])
        photo3[label] = np.array([x, -y, z])
    order = sorted(photo3, key=_LABEL_ORDER.__getitem__)
    points = {label: scale * (rot @ photo3[label]) + shift for label in order}
    marks = landmarks.points.astype(np.float64)
    marks3 = scale * (np.c_[marks[:, 0], -marks[:, 1], -marks[:, 2]] @ rot.T) + shift
    notes = not_neutral(points, head, set(given or ()))
    _lip_midpoints_slid(points, pixels, marks3, marks[:, :2], head, set(given or ()))
    _lips_in_contact(points, head, set(given or ()))
    _lips_level(points, head, set(given or ()))
    _eyes_open(points, head, set(given or ()))
    return {label: pixels[label] for label in order}, points, float(scale), notes


INNER_LIP_MIDPOINTS = {"2.6": ("2.2", "2.4"), "2.7": ("2.2", "2.5"), "2.8": ("2.3", "2.4"), "2.9": ("2.3", "2.5")}
"""The inner lip points the standard places midway along a contour, and the contour's ends."""


def _ring_path(ring: Sequence[int], start: int, end: int) -> list[int]:
    """The landmarks of ``ring`` from ``start`` to ``end`` the shorter way round (both included)."""
    i, j, n = ring.index(start), ring.index(end), len(ring)
    forward = [ring[(i + k) % n] for k in range((j - i) % n + 1)]
    backward = [ring[(i - k) % n] for k in range((i - j) % n + 1)]
    return forward if len(forward) <= len(backward) else backward


def _lip_midpoints_slid(points: dict[str, np.ndarray], pixels: dict[str, np.ndarray], marks3: np.ndarray,
                        marks2: np.ndarray, head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """Each inner lip midpoint (:data:`INNER_LIP_MIDPOINTS`) moved along the photo's own inner lip contour (the
    landmark model's ring, in 3D and in pixels alike) to the share of the way from the midline to the corner, across
    the face, that the receiving head's point has. "Midway" is read differently by the landmark model (its contour's
    middle landmark: 0.50-0.54 of the way on the astronaut) and by the head (half the arc: 0.64 on the upper lip,
    0.45 on the lower), and a calibration that slid the head's upper and lower contours apart, 0.7 mm from each other,
    sheared the lips where they meet: the bilabials' pressed lips showed a notched seal line. Where the point sits on
    its contour is the head's; the contour's shape, and so the lips' shape, stays the photo's."""
    from mpeg4fa.spec.landmark_points import LANDMARK_POINTS
    from mpeg4fa.tracking.landmarks import OPENING_RINGS

    ring = list(OPENING_RINGS["mouth"])
    for label, (middle, corner) in INNER_LIP_MIDPOINTS.items():
        if label in given or label not in points or not {label, middle, corner} <= head.keys():
            continue
        ends = [LANDMARK_POINTS[end].indices for end in (middle, corner)]
        if any(len(e) != 1 or e[0] not in ring for e in ends):
            continue
        path = _ring_path(ring, ends[0][0], ends[1][0])
        x = marks3[path, 0]
        along = np.maximum.accumulate((x - x[0]) / (x[-1] - x[0])) if abs(x[-1] - x[0]) > 1e-9 else None
        if along is None or along[-1] <= along[0]:
            continue
        share = (head[label][0] - head[middle][0]) / (head[corner][0] - head[middle][0])
        k = int(np.clip(np.searchsorted(along, share, side="right") - 1, 0, len(path) - 2))
        t = float(np.clip((share - along[k]) / max(along[k + 1] - along[k], 1e-12), 0.0, 1.0))
        points[label] = marks3[path[k]] + t * (marks3[path[k + 1]] - marks3[path[k]])
        pixels[label] = marks2[path[k]] + t * (marks2[path[k + 1]] - marks2[path[k]])


INNER_LIP_PAIRS = (("2.2", "2.3"), ("2.6", "2.8"), ("2.7", "2.9"))
"""Upper and lower inner lip points that meet in the neutral face."""


def _lips_in_contact(points: dict[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """An FDP describes the neutral face, whose lips are in contact (the facts file's neutral face
    definition, item 7, [S]); a photo of a smile or of speech has them apart, and a head calibrated to
    that gap shows its own teeth through it at rest. Each pair of inner lip points found (not given)
    further apart than the head's own pair closes about its midpoint to the head's gap (the lips' contact
    as the head models it; the points stay distinct). The texture coordinates stay on the photo's lips."""
    for upper, lower in INNER_LIP_PAIRS:
        if upper in points and lower in points and upper in head and lower in head and not {upper, lower} & given:
            gap = max(float(head[upper][1] - head[lower][1]), 0.0)
            if points[upper][1] - points[lower][1] > gap:   # apart (y up)
                middle = (points[upper][1] + points[lower][1]) / 2.0
                points[upper][1], points[lower][1] = middle + gap / 2.0, middle - gap / 2.0


LIP_CORNERS = {"left": ("8.3", "2.4"), "right": ("8.4", "2.5")}
"""The outer and inner lip corners of each side of the face."""
LIP_POINTS = ("2.2", "2.3", "2.4", "2.5", "2.6", "2.7", "2.8", "2.9",
              "8.1", "8.2", "8.3", "8.4", "8.5", "8.6", "8.7", "8.8", "8.9", "8.10")
"""The points of the lips' contours, which a smile bends."""


def _lips_level(points: dict[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """In the neutral face the line of the lips is horizontal, at the height of the lip corners (the facts
    file's neutral face definition, item 7, [S]); a smiling photo has its corners raised (the astronaut's
    6.6-8.0 mm over the line of her lips), and a head calibrated to them smiles in every expression. Each side's
    corners are brought to the line's height at the midline (inner lips 2.2/2.3, as the head's own corners sit
    against its own line), and the lip points between follow by the square of their share of the way out
    from the midline to the corner, which takes the bend of a smile out of the contours (an upper and lower inner
    lip pair by their mean share, so they stay in contact). Points given (a user's) stay, and a corner given keeps
    its side as found. The texture coordinates stay on the photo's lips, so the receiver paints the photo's lips
    onto the level ones."""
    if not {"2.2", "2.3"} <= points.keys() or not {"2.2", "2.3"} <= head.keys():
        return
    line = (points["2.2"][1] + points["2.3"][1]) / 2.0
    head_line = (head["2.2"][1] + head["2.3"][1]) / 2.0
    middle = (points["2.2"][0] + points["2.3"][0]) / 2.0
    for corners in LIP_CORNERS.values():
        seen = [c for c in corners if c in points and c in head]
        if not seen or set(corners) & given:
            continue
        drop = float(np.mean([line + (head[c][1] - head_line) - points[c][1] for c in seen]))
        reach = float(np.mean([points[c][0] for c in seen])) - middle
        if abs(reach) < 1e-6:
            continue
        share = {label: (points[label][0] - middle) / reach for label in LIP_POINTS if label in points}
        for pair in INNER_LIP_PAIRS:  # a pair moves as one, so the contact _lips_in_contact made stays
            if set(pair) <= share.keys():
                share.update(dict.fromkeys(pair, (share[pair[0]] + share[pair[1]]) / 2.0))
        for label, t in share.items():
            if t > 0.0 and label not in given:
                points[label][1] += drop * min(t, 1.0) ** 2


EYES = {"left": ("3.1", "3.3", "3.13", "3.9"), "right": ("3.2", "3.4", "3.14", "3.10")}
"""Each eye's upper and lower lid margin at the middle, and the folds above and below them."""
SHUT = 0.5
"""An eye whose lids are less than this share of the head's own opening apart is shut (a blink, a wink)."""


def _shut_eyes(points: Mapping[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]
               ) -> dict[str, tuple[float, float]]:
    """The eyes shut in the photo: side -> (the lids' gap, the head's own), mm."""
    out = {}
    for side, (upper, lower, _, _) in EYES.items():
        if {upper, lower} <= points.keys() and {upper, lower} <= head.keys() and not {upper, lower} & given:
            gap, own = points[upper][1] - points[lower][1], head[upper][1] - head[lower][1]
            if own > 0 and gap < SHUT * own:
                out[side] = (float(gap), float(own))
    return out


def _eyes_open(points: dict[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str]) -> None:
    """In the neutral face the lids are tangent to the iris (the facts file's neutral face definition, item 5,
    [S]): its lid opening is IRISD0, a FAPU every lid motion is measured in. A photo taken in a blink has its lids
    together, and a head calibrated to them had no opening at all (IRISD0 <= 0: no head could be made from the FDP).
    A shut eye (:data:`SHUT`) opens to the head's own opening about the middle of the photo's lids, its folds
    moving with the margins; the texture coordinates stay on the photo's closed lids."""
    for side in _shut_eyes(points, head, given):
        upper, lower, upper_fold, lower_fold = EYES[side]
        middle = (points[upper][1] + points[lower][1]) / 2.0
        head_middle = (head[upper][1] + head[lower][1]) / 2.0
        for margin, fold in ((upper, upper_fold), (lower, lower_fold)):
            move = middle + (head[margin][1] - head_middle) - points[margin][1]
            points[margin][1] += move
            if fold in points and fold not in given:
                points[fold][1] += move


NOTE_MM = 2.0
"""Lips apart, or corners over the line of the lips, by less than this (beyond the head's own) are not worth a
note: the landmark model reads the generic head's own rendered corners up to 1 mm high."""


def not_neutral(points: Mapping[str, np.ndarray], head: Mapping[str, np.ndarray], given: set[str] = frozenset()
                ) -> list[str]:
    """One line for each way the face found in a photo (``points``: as found, in the head's frame, mm) is not the
    neutral face, which the FDP is then made (:func:`_lips_in_contact`, :func:`_lips_level`, :func:`_eyes_open`), with
    the figure, so a user knows why the head does not smile, part its lips or shut its eyes as the photo does."""
    out = []
    gaps = [(points[u][1] - points[lo][1]) - max(float(head[u][1] - head[lo][1]), 0.0) for u, lo in INNER_LIP_PAIRS
            if {u, lo} <= points.keys() and {u, lo} <= head.keys() and not {u, lo} & given]
    if gaps and max(gaps) >= NOTE_MM:
        out.append(f"the lips are {max(gaps):.0f} mm apart in the photo; closed in the FDP, as the neutral face's are")
    if {"2.2", "2.3"} <= points.keys() and {"2.2", "2.3"} <= head.keys():
        line, head_line = ((p["2.2"][1] + p["2.3"][1]) / 2.0 for p in (points, head))
        lifts = [(points[c][1] - line) - (head[c][1] - head_line) for corners in LIP_CORNERS.values()
                 if not set(corners) & given for c in corners if c in points and c in head]
        lift = float(np.mean(lifts)) if lifts else 0.0
        if abs(lift) >= NOTE_MM:
            way = "over" if lift > 0 else "under"
            out.append(f"the lip corners sit {abs(lift):.0f} mm {way} the line of the lips in the photo "
                       f"({'a smile' if lift > 0 else 'turned down'}); level in the FDP, as the neutral face's are")
    for side, (gap, own) in _shut_eyes(points, head, given).items():
        out.append(f"the {side} eye is shut in the photo (its lids {max(gap, 0.0):.1f} mm apart); opened in the FDP "
                   f"as wide as the head's own ({own:.1f} mm), as the neutral face's eyes are")
    return out


def _generic_points() -> dict[str, np.ndarray]:
    from mpeg4fa.face import FaceModel
    return FaceModel.default().feature_points()


def side_view_of(landmarks: Landmarks) -> str:
    """Which side of the face a turned photo shows: "left" when the nose points to the image's left
    (the face's own left side toward the camera), else "right"."""
    nose = feature_points(landmarks)["9.3"][0]
    return "left" if nose < float(landmarks.points[:, 0].mean()) else "right"


def _merge_side(points: dict[str, np.ndarray], side: Landmarks, where: str) -> tuple[dict[str, np.ndarray], str, int]:
    """The front's head-frame points averaged with a turned photo's, on the side it shows and the midline
    (its far side is hidden: the model guesses it)."""
    from mpeg4fa.spec import FEATURE_POINTS

    view = side_view_of(side)
    facing = {fp.label for fp in FEATURE_POINTS if fp.side in (None, view)}
    _, other, _ = photo_points(side)
    used = [label for label in points if label in facing and label in other]
    merged = dict(points)
    for label in used:
        merged[label] = (points[label] + other[label]) / 2.0
    return merged, view, len(used)


def _head_mask(person: np.ndarray, pixels: Mapping[str, np.ndarray]) -> np.ndarray:
    """The person's head and neck: above the chin all of the person (face, hair, ears), below it only
    the band between the jaw's corners (the neck), so shoulders and collars do not count; a receiver's
    head wider than the face then wears the colours of the face's own sides."""
    height, width = person.shape
    rows, cols = np.mgrid[0:height, 0:width]
    chin = float(pixels["2.1"][1])
    left, right = sorted((float(pixels["2.13"][0]), float(pixels["2.14"][0])))
    return person & ((rows <= chin) | ((cols >= left) & (cols <= right)))


def _texture(photo: PhotoSource, image: np.ndarray, name: str, extend: bool,
             pixels: Mapping[str, np.ndarray], landmarks: np.ndarray) -> TextureImage:
    """The photo as the FDP's texture: with ``extend``, its background painted with the person's nearest
    colours (:func:`.segment.extend_person`); always with its eye openings and open mouth painted over
    (:func:`.segment.close_openings`: the receiver's head has eyes and teeth of its own); as a JPEG
    (quality 92) when it came as one, else a PNG."""
    from mpeg4fa.tracking.segment import close_openings, extend_person, person_mask

    stem = Path(name).stem if name else "photo"
    head = b"" if isinstance(photo, np.ndarray) else Path(photo).read_bytes()[:16]
    jpeg = head.startswith(b"\xff\xd8\xff")
    if extend:
        image = extend_person(image, _head_mask(person_mask(image, name), pixels))
    image = close_openings(image, landmarks)
    from PIL import Image
    buffer = io.BytesIO()
    if jpeg:
        Image.fromarray(image).save(buffer, format="JPEG", quality=92)
        return TextureImage(f"{stem}.jpg", "image/jpeg", buffer.getvalue())
    Image.fromarray(image).save(buffer, format="PNG")
    return TextureImage(f"{stem}.png", "image/png", buffer.getvalue())


def fdp_from_photo(photo: PhotoSource, *, side: PhotoSource | None = None,
                   points: Mapping[str, Sequence[float]] | None = None, where: str | None = None,
                   side_where: str | None = None, name: str | None = None, texture: bool = True,
                   extend_background: bool = True) -> PhotoFdp:
    """The FDP of the face in ``photo`` (a path or an RGB array): its feature points in 3D and, with
    ``texture``, the photo as its texture.

    ``points`` (label -> (x, y) pixels on the photo, e.g. a user's annotation) win over the found ones.
    ``extend_background``: the texture's background takes the person's nearest colours, so a receiver's
    head wider than the face wears skin and hair at its sides, not the wall (:mod:`.segment`).
    ``side``: a second photo of the face turned 20 to 60 degrees (the landmark model finds no face in a
    full profile); the points of the side it shows are the mean of both photos' estimates. One face
    is used (the largest, said in a warning); no face is a :class:`~.errors.NoFaceError` naming the photo.
    """
    image, label = read_photo(photo, where)
    landmarks = find_landmarks(image, label)
    pixels, points3, mm_per_pixel, notes = _photo_points(landmarks, given=points)
    side_info = None
    if side is not None:
        side_image, side_label = read_photo(side, side_where)
        side_marks = find_landmarks(side_image, side_label)
        points3, view, used = _merge_side(points3, side_marks, side_label)
        side_info = (side_label, view, used)
    height, width = image.shape[:2]
    tex = _texture(photo, image, label, extend_background, pixels, landmarks.points) if texture else None
    stem = name if name is not None else Path(label).stem
    fdp = fdp_from_front(points3, pixels, front_size=(width, height), texture=tex, name=stem)
    return PhotoFdp(fdp=fdp, image=image, landmarks=landmarks, pixels=pixels, points=points3, scale=mm_per_pixel,
                    side=side_info, notes=tuple(notes))

PREVIEW_VIEWS = ("front", "three-quarter")


def textured_head(made: PhotoFdp, method: str = "dffd"):
    """(face, texture): the head calibrated to the photo's FDP and the skin texture a receiver bakes
    from the FDP's photo (:func:`mpeg4fa.render.fdp_texture.bake_fdp_texture`)."""
    from mpeg4fa.render.fdp_texture import bake_fdp_texture

    face = made.calibrated(method)
    return face, bake_fdp_texture(face.mesh, made.fdp).baked.image


def marked_photo(made: PhotoFdp, height: int) -> np.ndarray:
    """The photo around the face, ``height`` pixels high, with the found feature points drawn on it
    (yellow: the face's left, cyan: its right, white: the midline)."""
    from PIL import Image, ImageDraw

    from mpeg4fa.spec import FEATURE_POINTS

    side = {fp.label: fp.side for fp in FEATURE_POINTS}
    x0, y0, x1, y1 = made.landmarks.box
    h, w = made.image.shape[:2]
    half = 0.75 * max(x1 - x0, y1 - y0)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    box = [int(max(cx - half, 0)), int(max(cy - half, 0)), int(min(cx + half, w)), int(min(cy + half, h))]
    zoom = height / (box[3] - box[1])
    crop = Image.fromarray(made.image[box[1]:box[3], box[0]:box[2]])
    crop = crop.resize((max(int(round(crop.width * zoom)), 1), height), Image.LANCZOS)
    draw = ImageDraw.Draw(crop)
    colours = {"left": (255, 230, 0), "right": (0, 220, 255), None: (255, 255, 255)}
    r = max(2.0, height / 160)
    for label, (x, y) in made.pixels.items():
        px, py = (x - box[0]) * zoom, (y - box[1]) * zoom
        draw.ellipse([px - r, py - r, px + r, py + r], fill=colours[side[label]], outline=(0, 0, 0))
    return np.asarray(crop)


def preview(made: PhotoFdp, method: str = "dffd", size: int = 384, extra: np.ndarray | None = None) -> np.ndarray:
    """One picture: the photo with its points, then the calibrated textured head front and three-quarter
    (``extra``: a further panel of the same height, e.g. a talking frame)."""
    from mpeg4fa.render import Renderer

    face, texture = textured_head(made, method)
    panels = [marked_photo(made, size)]
    for view in PREVIEW_VIEWS:
        with Renderer(face, width=size, height=size, samples=4, view=view, texture=texture) as renderer:
            panels.append(renderer.render(face.neutral()))
    if extra is not None:
        panels.append(extra)
    return np.concatenate(panels, axis=1)
