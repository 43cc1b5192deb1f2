"""Photo calibration for the editor (issue 17 item 4): pure functions over arrays, no server needed.

A front and a side photo are orthographic views of the head: the front shows x (to the image's
right) and y (up), the side z and y (a ``"left"`` photo has the nose toward the image's left, as
:mod:`mpeg4fa.render.texture` has it). The first placement of the feature points is the head's
own points projected into each photo and fitted to a box (around the head's silhouette on a plain
background, :func:`silhouette_box`, else centred, :func:`default_box`; :func:`fit_to_box`); the
user then drags the box (the points not yet dragged follow it) and the points. :func:`calibrate_from_photos`
turns the dragged points into 3D points (:func:`mpeg4fa.fdp.build.points_from_photos`), brought
back to the head's scale and place (photos carry no absolute size), and calibrates the head on
them (:meth:`mpeg4fa.face.FaceModel.calibrate`). :func:`bake` is
:func:`mpeg4fa.render.texture.bake_texture` on the calibrated head; :func:`photo_fdp` the FDP a
sender transmits (:func:`mpeg4fa.fdp.build.fdp_from_photos`, the front photo as its texture).
"""
from __future__ import annotations

import io
from typing import Mapping

import numpy as np

from mpeg4fa.web.edits import EditError

BOX_HEIGHT = 0.8
"""The default box's height as a share of the photo's height (centred)."""
MAX_PHOTO_PIXELS = 50_000_000
"""The most pixels a photo may have (a 50 MP photo is 150 MB decoded; a face needs far fewer)."""
_HIDDEN_SIDE = {"left": "right", "right": "left"}  # a side photo does not show the face's other half


def decode_photo(data: bytes, where: str) -> np.ndarray:
    """Image bytes (anything Pillow reads) as an (H, W, 3) uint8 RGB array; EditError otherwise. The size in its
    header is checked before any pixel is decoded: at most :data:`MAX_PHOTO_PIXELS`."""
    from PIL import Image, UnidentifiedImageError

    from mpeg4fa.render.images import image_rgb

    try:
        with Image.open(io.BytesIO(data)) as img:
            if img.width * img.height > MAX_PHOTO_PIXELS:
                raise EditError(f"the {where} photo is {img.width}x{img.height} pixels, more than "
                                f"{MAX_PHOTO_PIXELS // 1_000_000} million", where=where, hint="scale it down")
            rgb = image_rgb(img, turn=True)
    except UnidentifiedImageError:  # its text names the in-memory buffer ("<_io.BytesIO object at 0x...>")
        raise EditError(f"cannot read the {where} photo: no image format Pillow knows", where=where,
                        hint="send a PNG or JPEG image") from None
    except (OSError, ValueError, Image.DecompressionBombError) as exc:
        raise EditError(f"cannot read the {where} photo ({exc})", where=where,
                        hint="send a PNG or JPEG image") from None
    if rgb.shape[0] < 16 or rgb.shape[1] < 16:
        raise EditError(f"the {where} photo is only {rgb.shape[1]}x{rgb.shape[0]} pixels", where=where,
                        hint="at least 16x16")
    return rgb


def view_labels(head_mesh, view: str) -> tuple[str, ...]:
    """The feature points a photo from ``view`` shows: all on the front, one half and the middle on a side."""
    from mpeg4fa.spec import FEATURE_POINTS

    if view == "front":
        return tuple(head_mesh.fp_labels)
    hidden = {fp.label for fp in FEATURE_POINTS if fp.side == _HIDDEN_SIDE[view]}
    return tuple(label for label in head_mesh.fp_labels if label not in hidden)


def head_outline(head_mesh, view: str) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The head in ``view``'s plane, in mm: each shown point's (across, up) and the skin's box [a0, u0, a1, u1]."""
    from mpeg4fa.render.texture import VIEW_AXES

    across = np.asarray(VIEW_AXES[view][0])
    skin = head_mesh.vertices[head_mesh.part("skin")]
    flat = np.c_[skin @ across, skin[:, 1]]
    points = {label: np.array([head_mesh.fp(label) @ across, head_mesh.fp(label)[1]])
              for label in view_labels(head_mesh, view)}
    return points, np.r_[flat.min(axis=0), flat.max(axis=0)]


def default_box(size: tuple[int, int], outline_box: np.ndarray) -> list[float]:
    """A box centred in a (width, height) photo, BOX_HEIGHT of its height, with the head's aspect ratio."""
    width, height = size
    a0, u0, a1, u1 = outline_box
    h = BOX_HEIGHT * height
    w = min(h * (a1 - a0) / (u1 - u0), 0.95 * width)
    return [(width - w) / 2.0, (height - h) / 2.0, (width + w) / 2.0, (height + h) / 2.0]


PLAIN_BACKGROUND = 24
"""How far (0..255, per channel) a photo's border pixels may stray from their median for it to count as plain."""
FOREGROUND = 40
"""How far from the background colour a pixel must be to belong to the head."""


def silhouette_box(image: np.ndarray, outline_box: np.ndarray) -> list[float] | None:
    """The head's box found on a photo with a plain background, or None (a busy background, nothing found).

    The head's top, left and right are where its pixels start; the bottom follows from the head's own aspect
    ratio, since a photo usually cuts the neck. A head that touches the photo's top or sides gives None."""
    img = np.asarray(image, np.int16)
    h, w = img.shape[:2]
    border = np.concatenate([img[0], img[:, 0], img[:, -1]])  # not the bottom row: the neck or shoulders cross it
    background = np.median(border, axis=0)
    if np.percentile(np.abs(border - background).max(axis=1), 90) > PLAIN_BACKGROUND:
        return None
    head = np.abs(img - background).max(axis=2) > FOREGROUND
    rows = np.flatnonzero(head.sum(axis=1) > max(2, 0.01 * w))
    cols = np.flatnonzero(head.sum(axis=0) > max(2, 0.01 * h))
    if len(rows) < 0.1 * h or len(cols) < 0.1 * w:
        return None
    top, left, right = float(rows[0]), float(cols[0]), float(cols[-1] + 1)
    if top <= 0 or left <= 0 or right >= w:
        return None
    a0, u0, a1, u1 = outline_box
    return [left, top, right, top + (right - left) * (u1 - u0) / (a1 - a0)]


def first_boxes(head_mesh, images: Mapping[str, np.ndarray], side_view: str) -> dict[str, list[float]]:
    """Each photo's first box: around the head where the background is plain (:func:`silhouette_box`),
    else centred (:func:`default_box`)."""
    boxes = {}
    for key, view in (("front", "front"), ("side", side_view)):
        _, outline = head_outline(head_mesh, view)
        image = images[key]
        boxes[key] = silhouette_box(image, outline) or default_box((image.shape[1], image.shape[0]), outline)
    return boxes


def check_box(box, size: tuple[int, int], where: str) -> list[float]:
    b = np.asarray(box, float)
    if b.shape != (4,) or not np.isfinite(b).all() or b[2] - b[0] < 2 or b[3] - b[1] < 2:
        raise EditError(f"a box is [x0, y0, x1, y1] with x1 > x0 and y1 > y0 (pixels), got {box!r}", where=where)
    return b.tolist()


def fit_to_box(points: Mapping[str, np.ndarray], outline_box: np.ndarray, box) -> dict[str, list[float]]:
    """Head-plane points (mm, up positive) mapped so that the head's box lands on ``box`` (pixels, y down)."""
    a0, u0, a1, u1 = outline_box
    x0, y0, x1, y1 = box
    sx, sy = (x1 - x0) / (a1 - a0), (y1 - y0) / (u1 - u0)
    return {label: [round(float(x0 + (p[0] - a0) * sx), 3), round(float(y1 - (p[1] - u0) * sy), 3)]
            for label, p in points.items()}


def guess(head_mesh, sizes: Mapping[str, tuple[int, int]], side_view: str, boxes: Mapping[str, list] | None = None,
          dragged: Mapping[str, Mapping[str, list]] | None = None):
    """The placement: {"front": {label: [x, y]}, "side": {label: [z, y]}, "box": {"front": .., "side": ..},
    "dragged": {"front": [labels], "side": [labels]}}. The points fitted to the box are guesses; those in
    ``dragged`` ({view: {label: [x, y]}}) were put by the user and stay where they were put."""
    out: dict = {"front": {}, "side": {}, "box": {}, "dragged": {}}
    for key, view in (("front", "front"), ("side", side_view)):
        points, outline = head_outline(head_mesh, view)
        box = [round(float(v), 3) for v in (boxes or {}).get(key) or default_box(sizes[key], outline)]
        placed = fit_to_box(points, outline, box)
        held = {k: [round(float(x), 3), round(float(y), 3)] for k, (x, y) in ((dragged or {}).get(key) or {}).items()}
        _known_in(placed, held, key)
        out[key] = {**placed, **held}
        out["box"][key] = box
        out["dragged"][key] = sorted(held)
    return out


def find_points(head_mesh, image: np.ndarray, view: str, where: str) -> tuple[dict[str, list[float]], list[float]]:
    """(points, box): the feature points the landmark model finds on a photo (those ``view`` shows), where an FDP
    made from the photo puts them (:func:`mpeg4fa.tracking.photo_points`: the inner lip midpoints at the head's own
    share of their contour), and the head's box fitted to them (least squares per axis), so that the points it
    does not find (ears, hairline, tongue...) follow the found face. EditError when there is no face or no model."""
    from mpeg4fa.tracking import TrackingError, find_landmarks, photo_points

    try:
        landmarks = find_landmarks(image, f"{where} photo")
    except TrackingError as exc:
        hint = exc.hint if view == "front" else ("the landmark model finds faces turned up to about 60 degrees, "
                                                 "not a profile: place the side points by hand")
        raise EditError(exc.message, where=where, hint=hint) from None
    found, _, _ = photo_points(landmarks, {label: head_mesh.fp(label) for label in head_mesh.fp_labels})
    outline_points, outline = head_outline(head_mesh, view)
    labels = [label for label in found if label in outline_points]
    head = np.array([outline_points[label] for label in labels])
    pix = np.array([found[label][:2] for label in labels])
    sx, cx = np.polyfit(head[:, 0], pix[:, 0], 1)           # x = cx + sx * across
    sy, cy = np.polyfit(head[:, 1], pix[:, 1], 1)           # y = cy + sy * up (sy < 0: y grows down)
    a0, u0, a1, u1 = outline
    if sx <= 0 or sy >= 0:
        raise EditError("the face found runs the wrong way across or up the photo", where=where,
                        hint="check for a mirrored or upside-down photo")
    box = [float(cx + sx * a0), float(cy + sy * u1), float(cx + sx * a1), float(cy + sy * u0)]
    return {label: [round(float(found[label][0]), 3), round(float(found[label][1]), 3)] for label in labels}, box


def _known_in(placed: Mapping, held: Mapping, where: str) -> None:
    unknown = sorted(set(held) - set(placed))
    if unknown:
        raise EditError(f"labels {', '.join(unknown)} are not feature points this photo shows", where=where,
                        hint="drag only the points the page draws on it")


def _rescale(points: Mapping[str, np.ndarray], head_mesh) -> dict[str, np.ndarray]:
    """Photo-pixel 3D points moved and scaled uniformly onto the head's own points (least squares)."""
    labels = list(points)
    p = np.array([points[k] for k in labels])
    h = np.array([head_mesh.fp(k) for k in labels])
    pc, hc = p - p.mean(axis=0), h - h.mean(axis=0)
    s = float(np.sum(pc * hc) / max(np.sum(pc * pc), 1e-12))
    return {k: s * row + h.mean(axis=0) for k, row in zip(labels, pc)}


def calibrate_from_photos(face, front: Mapping[str, list], side: Mapping[str, list], side_view: str,
                          method: str = "dffd"):
    """(the calibrated FaceModel, the 3D targets in head mm, the report as a dict)."""
    from mpeg4fa.fdp import Fdp
    from mpeg4fa.fdp.build import points_from_photos

    _known(face.mesh, front, "front")
    _known(face.mesh, side, "side")
    targets = _rescale(points_from_photos(front, side, side_view=side_view), face.mesh)
    calibrated = face.calibrate(Fdp.from_points(targets), method=method)
    report = calibrated.calibration.as_dict() if getattr(calibrated, "calibration", None) else {}
    errors = [float(np.linalg.norm(calibrated.mesh.fp(k) - v)) for k, v in targets.items()]
    report.update(points=len(targets), max_point_error_mm=max(errors))
    return calibrated, targets, report


def skin_texture_mapping(head_mesh, origin: np.ndarray, triangles: np.ndarray) -> dict[str, list]:
    """The head's skin triangles that the edited mesh still has, in its vertex numbering (``origin``: each
    edited vertex's head vertex; ``triangles``: its (T, 3) triangles), with their corners' texture
    coordinates, for showing the baked texture on it: {"indices": flat, "uvs": flat (u, v) per corner, v up}."""
    n = len(origin) + 1
    inverse = np.full(head_mesh.n_vertices, -1, np.int64)
    inverse[np.asarray(origin, np.int64)] = np.arange(len(origin))
    tri = inverse[np.asarray(head_mesh.triangles["skin"], np.int64)]

    def keys(t: np.ndarray) -> np.ndarray:
        s = np.sort(t, axis=1) + 1
        return (s[:, 0] * n + s[:, 1]) * n + s[:, 2]
    kept = (tri >= 0).all(axis=1) & np.isin(keys(tri), keys(np.asarray(triangles, np.int64)))
    uvs = np.asarray(head_mesh.corner_uvs["skin"], float)[kept]
    return {"indices": tri[kept].ravel().tolist(), "uvs": np.round(uvs, 6).ravel().tolist()}


def _known(head_mesh, points: Mapping, where: str) -> None:
    unknown = sorted(set(points) - set(head_mesh.fp_labels))
    if unknown:
        raise EditError(f"labels {', '.join(unknown)} are not feature points of this head", where=where)


def bake(face, images: Mapping[str, np.ndarray], front: Mapping, side: Mapping, side_view: str, size: int = 512):
    """The skin texture baked from the photos onto ``face`` (the calibrated head): (H, W, 3) uint8."""
    from mpeg4fa.render.texture import PhotoView, bake_texture

    return bake_texture(face.mesh, PhotoView(images["front"], dict(front), "front"),
                        PhotoView(images["side"], dict(side), side_view), size=size).image


def encode_png(image: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(image).save(buf, format="PNG")
    return buf.getvalue()


def photo_fdp(front: Mapping, side: Mapping, side_view: str, front_image: np.ndarray, name: str):
    """The FDP of the photos' points, with the front photo (PNG) as its texture and texture coordinates."""
    from mpeg4fa.fdp.build import fdp_from_photos
    from mpeg4fa.fdp.model import TextureImage

    texture = TextureImage(f"{name}.front.png", "image/png", encode_png(front_image))
    return fdp_from_photos(front, side, side_view=side_view, texture=texture, name=name)
