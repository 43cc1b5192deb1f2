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
definition, :mod:`.neutral_face`): a photo's open or smiling lips are closed and levelled and a shut eye opened, in
the points only, and the inner lip midpoints sit where the receiving head has its own along the contour. The photo
goes into the FDP as its texture with every point's texture coordinate (FDP case 3, as ``encode --front`` does), so
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
from mpeg4fa.tracking.neutral_face import make_neutral
from mpeg4fa.tracking.points import feature_points

__all__ = ["PhotoFdp", "fdp_from_photo", "photo_points", "read_photo"]

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
    """What of the photo's face was not neutral and was made so in the FDP, one line each
    (:func:`.neutral_face.not_neutral`)."""
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
    return read_image(photo, "photo", name, turn=True), name


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
    """:func:`photo_points`, and the lines of :func:`.neutral_face.not_neutral` on the points as found."""
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
    notes = make_neutral(points, pixels, marks3, marks[:, :2], head, set(given or ()))
    return {label: pixels[label] for label in order}, points, float(scale), notes


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
