"""Build the FDP a sender transmits from what a user has: a face mesh or two annotated photos.

* :func:`fdp_from_mesh`: the user's own mesh (e.g. from :func:`~mpeg4fa.fdp.obj.read_obj`)
  with each feature point given as a vertex index or as coordinates; the FDP carries
  the mesh, and the points' uvs when the mesh has them.
* :func:`fdp_from_front`: one front photo whose points have depth (a landmark model's), the
  photo as the texture.
* :func:`fdp_from_photos`: a front and a side photo with annotated 2D feature
  points (``{label: [x, y]}`` in pixels, x right, y down, as in
  :class:`mpeg4fa.render.texture.PhotoView`). Depth comes from the side photo by
  matching bounding boxes (:func:`points_from_photos`); the front photo can go
  along as the FDP's texture, with each point's texture coordinate into it.

Points files are JSON, read by :func:`read_points_json` with errors at line:column.
"""
from __future__ import annotations

import os
import struct
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping, Sequence

import numpy as np

from mpeg4fa.fdp.errors import FdpError, read_bytes
from mpeg4fa.fdp.json_form import _decode, _Doc, _kind, _parse
from mpeg4fa.fdp.model import (LABEL_INDEX, MAX_COORDINATE, Fdp, FdpMesh, FdpValueError, TextureImage,
                               first_unbounded)
from mpeg4fa.spec import FEATURE_POINT_MIRROR, FEATURE_POINTS

SIDE_VIEWS = ("left", "right")
MIN_SHARED_EXTENT = 0.05
"""Smallest vertical extent of the shared labels, as a fraction of the photo's annotated extent."""
_LABEL_HINT = "labels are 2.1 .. 11.6 (groups 2-11 of the standard)"


# ---- mirror twins: the ``side`` and ``mirror`` columns of spec/feature_points.csv ---------------

MIRROR_TWINS: Mapping[str, str] = MappingProxyType(dict(FEATURE_POINT_MIRROR))
"""Each sided feature point's left/right twin (both ways: 3.5 -> 3.6 and 3.6 -> 3.5), from the spec data."""
_ON_LEFT = frozenset(fp.label for fp in FEATURE_POINTS if fp.side == "left")  # +x, the face's left

_GROUP = {fp.label: fp.group for fp in FEATURE_POINTS}
_UPPER = tuple(label for label, g in _GROUP.items() if g in (3, 4))        # eyes, eyebrows
_LOWER = tuple(label for label, g in _GROUP.items() if g in (2, 8))        # mouth, chin, jaw
# Coarse anatomy (true of any face) for the side photo's direction check: (points ahead, points behind, names).
_DEPTH_ORDER = (
    (("9.3",) + tuple(label for label, g in _GROUP.items() if g == 8),
     tuple(label for label, g in _GROUP.items() if g == 10) + ("11.6",), "the nose tip and lips",
     "the ears and the back of the skull"),
    (("9.3",), tuple(label for label, g in _GROUP.items() if g == 3), "the nose tip", "the eyes"),
)


# ---- from a mesh ------------------------------------------------------------------------------


def fdp_from_mesh(mesh: FdpMesh, points: Mapping[str, int | Sequence[float]], *, name: str = "",
                  textures: Sequence[TextureImage] = (), fapu: Mapping[str, float] | None = None) -> Fdp:
    """An FDP carrying ``mesh``, its feature points given as vertex indices or as [x, y, z].

    When every point is a vertex and the mesh has uvs, the points get those uvs
    as texture coordinates (an FDP gives texture coordinates for all of its
    points or none, and an explicit point has no uv).
    """
    if not isinstance(mesh, FdpMesh):
        raise FdpValueError(f"mesh must be an FdpMesh, got {type(mesh).__name__}", ("mesh",))
    coords: dict[str, np.ndarray] = {}
    vertex: dict[str, int] = {}
    for label, value in points.items():
        _check_label(label, "feature_points")
        if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
            if not 0 <= value < len(mesh.vertices):
                raise FdpValueError(f"feature point {label} is vertex {value}, but the mesh has "
                                    f"{len(mesh.vertices)} vertices (0 .. {len(mesh.vertices) - 1})",
                                    ("feature_points", label))
            vertex[label] = int(value)
            coords[label] = mesh.vertices[value]
        else:
            coords[label] = _point(value, 3, f"feature point {label}", "a vertex index or [x, y, z]",
                                   ("feature_points", label))
    uv = None
    if mesh.uvs is not None and coords and len(vertex) == len(coords):
        uv = {label: mesh.uvs[i] for label, i in vertex.items()}
    return Fdp.from_points(coords, uv, textures=tuple(textures), mesh=mesh, fapu=None if fapu is None else dict(fapu),
                           name=name)


def _check_label(label: Any, part: str) -> None:
    if not isinstance(label, str) or label not in LABEL_INDEX:
        raise FdpValueError(f"unknown feature point label {label!r}; {_LABEL_HINT}", (part, str(label)), key=True)


def _point(value: Any, n: int, what: str, forms: str, where: tuple[Any, ...]) -> np.ndarray:
    """A finite (n,) float array within +-:data:`~mpeg4fa.fdp.model.MAX_COORDINATE`, or an FdpValueError naming
    ``what`` (a photo point at 1e308 overflowed the depth check's mean: a numpy warning, fuzz points:29937@0)."""
    try:
        p = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        p = np.empty(0)
    if p.shape != (n,) or first_unbounded(p) is not None:
        raise FdpValueError(f"{what} must be {forms} (finite numbers within +-{MAX_COORDINATE:g}), got {value!r}",
                            where)
    return p


# ---- points files -------------------------------------------------------------------------------


def read_points_json(path: str | os.PathLike[str]) -> dict[str, int | tuple[float, ...]]:
    """Read ``{label: [x, y]}`` (photo pixels) or ``{label: vertex index or [x, y, z]}`` (a mesh's points).

    The two kinds are not mixed in one file: photo points have no depth and
    mesh points no pixels. Every fault is an :class:`FdpError` at its line:column.
    """
    return parse_points_json(read_bytes(path), str(path))


def parse_points_json(data: bytes, name: str) -> dict[str, int | tuple[float, ...]]:
    """:func:`read_points_json` on bytes already in memory (an upload); ``name`` locates the faults."""
    text = _decode(data, name)
    doc = _Doc(text, name)
    points = doc.obj(_parse(text, name, "a feature points file"), (), "a feature points file", ())
    out: dict[str, int | tuple[float, ...]] = {}
    first_photo: bool | None = None
    for label, value in points.items():
        if label not in LABEL_INDEX:
            raise doc.fail((label,), f"unknown feature point label {label!r}", _LABEL_HINT, key=True)
        out[label] = _points_entry(doc, label, value)
        photo = isinstance(out[label], tuple) and len(out[label]) == 2  # type: ignore[arg-type]
        if first_photo is None:
            first_photo, first = photo, label
        elif photo != first_photo:
            kinds = ("photo pixels [x, y]", "a mesh point (vertex index or [x, y, z])")
            raise doc.fail((label,), f"point {label} is {kinds[not photo]} but {first} is {kinds[photo]}",
                           "a points file holds the points of one photo, or of one mesh")
    return out


def _points_entry(doc: _Doc, label: str, value: Any) -> int | tuple[float, ...]:
    if isinstance(value, int) and not isinstance(value, bool):
        return doc.integer(value, (label,), f"vertex index of {label}", 0, 2**63 - 1)
    if isinstance(value, list) and len(value) in (2, 3):
        return tuple(doc.number(v, (label, i), f"coordinate of point {label}") for i, v in enumerate(value))
    got = f"an array of {len(value)} values" if isinstance(value, list) else _kind(value)
    raise doc.fail((label,), f"point {label} must be [x, y], [x, y, z] or a vertex index, got {got}",
                   "photo points are [x, y] pixels; mesh points a vertex index or [x, y, z]")


# ---- from a front and a side photo --------------------------------------------------------------


def points_from_photos(front: Mapping[str, Sequence[float]], side: Mapping[str, Sequence[float]], *,
                       side_view: str) -> dict[str, np.ndarray]:
    """3D feature points from their pixel positions on a front and a side photo (orthographic views).

    x and y come from the front photo, z from the side photo, once the side
    photo is scaled so that the labels annotated on both span the same height as
    on the front. The result is in front-photo pixels, +x toward the face's
    left, +y up, +z out of the face, with the origin at the centre of the
    bounding box of the front photo's points (x, y) and of the side photo's (z).

    A point needs both photos, with one exception: a point seen only on the
    front whose mirror twin (:data:`MIRROR_TWINS`) is on the side photo takes
    the twin's depth, as a face is nearly symmetric; a side photo shows one half
    of the face, so this gives the hidden half. Other points are left out.
    """
    if side_view not in SIDE_VIEWS:
        raise FdpValueError(f"side_view must be 'left' or 'right', got {side_view!r} (a photo of the face's "
                            "left side has the nose pointing to the image's left)", ("side_view",))
    f = _photo_points(front, "front")
    s = _photo_points(side, side_view)
    _check_front_across(f)
    _check_upright(f, "front")
    _check_upright(s, side_view)
    scale = _side_scale(f, s, side_view)
    fxy = np.array(list(f.values()))
    centre = (fxy.min(axis=0) + fxy.max(axis=0)) / 2.0
    sx = np.array([p[0] for p in s.values()])
    across = (sx - (sx.min() + sx.max()) / 2.0) * scale
    depth = dict(zip(s, -across if side_view == "left" else across))  # a left photo shows +z to the image's left
    _check_depth(depth, side_view)
    out = {}
    for label in sorted(f, key=LABEL_INDEX.__getitem__):
        z = depth[label] if label in depth else depth.get(MIRROR_TWINS.get(label, ""))
        if z is not None:
            x, y = f[label] - centre
            out[label] = np.array([x, -y, z])
    return out


def _photo_points(points: Mapping[str, Sequence[float]], view: str) -> dict[str, np.ndarray]:
    if not isinstance(points, Mapping):
        raise FdpValueError(f"{view} photo points must be a mapping {{label: (x, y)}}, got {type(points).__name__}",
                            (view,))
    out = {}
    for label, xy in points.items():
        _check_label(label, view)
        out[label] = _point(xy, 2, f"{view} photo point {label}", "(x, y) pixels", (view, label))
    return out


def _mean_of(values: Mapping[str, float], labels: Sequence[str]) -> float | None:
    present = [values[label] for label in labels if label in values]
    return float(np.mean(present)) if present else None


def _check_front_across(front: Mapping[str, np.ndarray]) -> None:
    """Every twin pair on the front photo has its face-left point on the image's right."""
    for label, other in MIRROR_TWINS.items():
        if label in _ON_LEFT and label in front and other in front and front[label][0] < front[other][0]:
            raise FdpValueError(
                f"front photo points run the wrong way across the image: {label} (face's left) is left of "
                f"{other} (face's right), but the face's left side should be on the image's right (check for "
                "swapped left/right labels, a mirrored photo, or a side photo given as the front)", ("front", label))


def _check_upright(points: Mapping[str, np.ndarray], view: str) -> None:
    """Eyes and eyebrows above the mouth and chin (image y grows downward)."""
    heights = {label: p[1] for label, p in points.items()}
    up, down = _mean_of(heights, _UPPER), _mean_of(heights, _LOWER)
    if up is not None and down is not None and up > down:
        raise FdpValueError(f"{view} photo points run the wrong way up the image: the eyes and eyebrows "
                            "(groups 3, 4) lie below the mouth and chin (groups 2, 8) (check for an upside-down "
                            "photo or y measured upward; pixel y grows downward)", (view,))


def _side_scale(front: Mapping[str, np.ndarray], side: Mapping[str, np.ndarray], view: str) -> float:
    """Front pixels per side pixel: the ratio of the heights the shared labels span on the two photos."""
    shared = [label for label in front if label in side]
    if len(shared) < 2:
        def some(labels) -> str:
            labels = list(labels)
            return ", ".join(labels[:6]) + (f" and {len(labels) - 6} more" if len(labels) > 6 else "") or "none"
        raise FdpValueError(f"{len(shared)} label(s) annotated on both photos ({some(shared)}; front: {some(front)}; "
                            f"{view}: {some(side)}); at least 2 are needed to match their scales (annotate e.g. "
                            "the nose tip 9.3 and the chin 2.1 on both)", (view,))
    extents = []
    for name, points in (("front", front), (view, side)):
        xy = np.array(list(points.values()))
        extent = float(np.ptp([points[label][1] for label in shared]))
        if extent <= MIN_SHARED_EXTENT * float(np.ptp(xy, axis=0).max()):
            raise FdpValueError(f"the labels on both photos ({', '.join(shared)}) span only {extent:.3g} px "
                                f"vertically on the {name} photo, too little to match the photos' scales "
                                "(annotate points far apart vertically on both, e.g. 11.1 hairline, 9.3 nose tip, "
                                "2.1 chin)", (name,))
        extents.append(extent)
    return extents[0] / extents[1]


def _check_depth(depth: Mapping[str, float], view: str) -> None:
    """The nose points the way the view says: nose and lips nearer the face's front than eyes and ears."""
    for ahead, behind, ahead_name, behind_name in _DEPTH_ORDER:
        near, far = _mean_of(depth, ahead), _mean_of(depth, behind)
        if near is not None and far is not None and near < far:
            raise FdpValueError(
                f"{view} photo points run the wrong way across the image: {ahead_name} lie behind {behind_name}; "
                f"in a {view!r} photo the nose should point to the image's {view} (check the side_view name, "
                "a mirrored photo or swapped labels)", (view,))


def fdp_from_photos(front_points: Mapping[str, Sequence[float]], side_points: Mapping[str, Sequence[float]], *,
                    side_view: str = "left", front_size: tuple[int, int] | None = None,
                    texture: TextureImage | None = None, name: str = "") -> Fdp:
    """An FDP whose points come from a front and a side photo (:func:`points_from_photos`).

    With ``texture`` (the front photo, encoded) the FDP carries it and each
    point's texture coordinate into it, (x / width, 1 - y / height) of its front
    pixel position, as MPEG-4 texture-maps a face from the sender's photo.
    ``front_size`` (width, height) is read from the PNG or JPEG header when not
    given; given alone, it still yields the texture coordinates.
    """
    points = points_from_photos(front_points, side_points, side_view=side_view)
    size = _texture_size(texture, front_size)
    uv = None
    if size is not None:
        front = _photo_points(front_points, "front")
        uv = _texture_coords({label: front[label] for label in points}, size)
    return Fdp.from_points(points, uv, textures=() if texture is None else (texture,), name=name)


def fdp_from_front(points: Mapping[str, Sequence[float]], front_points: Mapping[str, Sequence[float]], *,
                   front_size: tuple[int, int] | None = None, texture: TextureImage | None = None,
                   name: str = "") -> Fdp:
    """An FDP from one front photo whose points already have depth (e.g. from a face landmark model).

    ``points`` are the 3D feature points (+x toward the face's left, +y up, +z out of the face, any
    unit); ``front_points`` the same labels' pixel positions on the photo, which give each point's
    texture coordinate into ``texture`` (the photo) as :func:`fdp_from_photos` does. Without a side
    photo nothing else is needed: the landmark model's depth stands in for it.
    """
    coords = {}
    for label, value in points.items():
        _check_label(label, "points")
        coords[label] = _point(value, 3, f"feature point {label}", "[x, y, z]", ("points", label))
    front = _photo_points(front_points, "front")
    if set(front) != set(coords):
        differ = sorted(set(front) ^ set(coords), key=LABEL_INDEX.__getitem__)
        raise FdpValueError(f"the 3D points and the front photo's points must name the same labels; differ on "
                            f"{', '.join(differ)}", ("front",))
    _check_front_across(front)
    _check_upright(front, "front")
    size = _texture_size(texture, front_size)
    uv = None if size is None else _texture_coords(front, size)
    return Fdp.from_points(coords, uv, textures=() if texture is None else (texture,), name=name)


def _texture_size(texture: TextureImage | None, front_size: tuple[int, int] | None) -> tuple[int, int] | None:
    if texture is not None and not isinstance(texture, TextureImage):
        raise FdpValueError(f"texture must be a TextureImage, got {type(texture).__name__}", ("textures",))
    header = None if texture is None else image_size(texture.data)
    if front_size is None:
        if texture is not None and header is None:
            raise FdpValueError(f"cannot read the size of texture {texture.name!r} ({texture.media_type}); pass "
                                "front_size=(width, height) of the front photo", ("textures",))
        return header
    if (not isinstance(front_size, (tuple, list)) or len(front_size) != 2
            or not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v > 0 for v in front_size)):
        raise FdpValueError(f"front_size must be (width, height) in pixels, got {front_size!r}", ("front_size",))
    size = (int(front_size[0]), int(front_size[1]))
    if header is not None and header != size:
        raise FdpValueError(f"front_size {size} differs from the texture's own size {header} (the texture must be "
                            "the front photo the points were annotated on)", ("front_size",))
    return size


def _texture_coords(front: Mapping[str, np.ndarray], size: tuple[int, int]) -> dict[str, np.ndarray]:
    """(u, v) = (x / width, 1 - y / height): v grows upward from the photo's bottom edge."""
    width, height = size
    uv = {label: np.array([p[0] / width, 1.0 - p[1] / height]) for label, p in front.items()}
    for label, (u, v) in uv.items():
        if not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
            raise FdpValueError(f"front photo point {label} at {front[label].tolist()} lies outside the "
                                f"{width}x{height} photo (check front_size and the annotation)", ("front", label))
    return uv


# ---- textures ----------------------------------------------------------------------------------

_PNG = b"\x89PNG\r\n\x1a\n"
_JPEG = b"\xff\xd8\xff"
_JPEG_SOF = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}   # frame headers; C4/C8/CC are other segments


def texture_from_file(path: str | os.PathLike[str]) -> TextureImage:
    """The image file at ``path`` as a texture (bytes kept as they are), typed by its first bytes."""
    name = str(path)
    data = read_bytes(path)
    if data.startswith(_PNG):
        media_type = "image/png"
    elif data.startswith(_JPEG):
        media_type = "image/jpeg"
    else:
        raise FdpError.at_byte(name, 0, "not a PNG or JPEG image (unknown first bytes)",
                               "FDP textures are PNG or JPEG files; convert the photo to one of them")
    return TextureImage(Path(path).name, media_type, data)


def _one_ihdr(data: bytes) -> bool:
    """Whether the PNG's chunks before its image data hold one IHDR (decoders take the last of several)."""
    pos, seen = 8, 0
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I", data[pos:pos + 4])[0], data[pos + 4:pos + 8]
        if kind in (b"IDAT", b"IEND"):
            break
        seen += kind == b"IHDR"
        pos += 12 + length
    return seen == 1


def image_size(data: bytes) -> tuple[int, int] | None:
    """(width, height) from a PNG or JPEG header, or None when ``data`` is neither or is cut short."""
    if data.startswith(_PNG) and data[12:16] == b"IHDR" and len(data) >= 24:
        return struct.unpack(">II", data[16:24]) if _one_ihdr(data) else None
    if not data.startswith(_JPEG):
        return None
    pos = 2
    while pos + 4 <= len(data) and data[pos] == 0xFF:
        marker = data[pos + 1]
        if marker == 0xFF:                  # fill byte before a marker
            pos += 1
        elif marker in _JPEG_SOF:
            if pos + 9 > len(data):
                return None
            height, width = struct.unpack(">HH", data[pos + 5:pos + 9])
            return width, height
        elif marker == 0x01 or 0xD0 <= marker <= 0xD8:  # markers without a length
            pos += 2
        elif marker in (0xD9, 0xDA):        # end of image, start of scan: no frame header before it
            return None
        else:
            pos += 2 + struct.unpack(">H", data[pos + 2:pos + 4])[0]
    return None
