"""The sender's texture (FDP case 3): an image and its feature points' texture coordinates on our head.

>>> sent = bake_fdp_texture(face.mesh, fdp)          # face calibrated to fdp
>>> Renderer(face, texture=sent.image)

An FDP may carry a texture image and, for each of its feature points, the
point's texture coordinate in that image (facts file: FDP ``textureCoord``;
``spec/FDP_STREAM.md`` ``TXCO``/``TXIM``). The sender's image is not in our
head's UV layout, so it is resampled into it:

1. **Map** (:func:`texture_map`): the feature points' 3D positions on the head
   (the calibrated neutral head, so they sit where the sender put them) and their
   texture coordinates define a smooth map from 3D to the image: the face
   layer's thin-plate RBF with an affine part (:class:`mpeg4fa.face.rbf.RbfField`,
   the calibration's own interpolator), exact at every feature point. Every vertex
   and every skin texel gets its coordinates in the sender's image from it.
2. **Camera**: the affine part of the map is an orthographic camera; the cross
   product of its image-x and image-up gradients points toward it. A texel is seen
   when it faces that camera and no other surface lands in front of it where it
   lands in the image (a depth map of the whole head drawn at the mapped vertex
   positions, :func:`.texture.projected_depth_map`), and it lands inside the
   head's outline there.
3. **Bake**: seen texels take the image's colour (bilinear); the rest (the sides
   and back a front photo does not show) are filled from the seen skin near them,
   and off-skin texels repeat their nearest skin texel across seams, all as the
   photo baker does (:func:`.texture.assemble`).

Texture coordinates follow the FDP's convention (``mpeg4fa.fdp.build``): u to
the right from the image's left edge, v up from its bottom edge, both in [0, 1];
pixel x = u * width, y = (1 - v) * height (x right, y down, as
:class:`.texture.PhotoView` points). Only the first texture of an FDP is used.
"""
from __future__ import annotations

import io
from dataclasses import dataclass

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.rbf import RbfField
from mpeg4fa.fdp.model import Fdp, TextureImage
from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.images import image_rgb
from mpeg4fa.render.texture import (BakedTexture, assemble, projected_depth_map, sample_projected, skin_texels,
                                    uv_rasterise)

__all__ = ["FdpTexture", "TextureMap", "bake_fdp_texture", "decode_texture", "texture_map", "fdp_skin_texture"]

MIN_CONTROLS = 4   # the RBF's affine part needs 4 points not in one plane


@dataclass(frozen=True, eq=False)
class TextureMap:
    """Where points of the head land in the sender's image.

    ``field`` maps 3D points to (u, v); ``toward`` is the unit direction toward
    the camera of its affine part, ``scale`` that camera's pixels per mm across
    and up, ``residual`` the RMS distance (pixels) between the feature points'
    texture coordinates and the affine camera alone (0 for an orthographic photo
    of exactly this head; large when the photo is not of a similar head or not
    orthographic).
    """

    field: RbfField
    size: tuple[int, int]          # the image's (width, height)
    labels: tuple[str, ...]
    toward: np.ndarray             # (3,)
    scale: tuple[float, float]
    residual: float

    def uv(self, points: np.ndarray) -> np.ndarray:
        """(N, 2) texture coordinates (u right, v up) of 3D points."""
        return self.field(np.asarray(points, float))

    def project(self, points: np.ndarray) -> np.ndarray:
        """(N, 3): pixel x, y in the image and depth toward its camera (mm, larger = nearer)."""
        p = np.asarray(points, float)
        uv = self.uv(p)
        width, height = self.size
        return np.c_[uv[:, 0] * width, (1.0 - uv[:, 1]) * height, p @ self.toward]


@dataclass(frozen=True, eq=False)
class FdpTexture:
    """The sender's texture baked into the head's UV layout, and the map that placed it.

    ``image`` is ready for ``Renderer(texture=...)``; ``vertex_coords`` are every
    vertex's (u, v) in the sender's image; ``baked.coverage`` marks the skin texels
    the image shows (the others were filled).
    """

    baked: BakedTexture
    map: TextureMap
    vertex_coords: np.ndarray      # (V, 2) float64, u right, v up
    name: str

    @property
    def image(self) -> np.ndarray:
        return self.baked.image

    @property
    def coverage(self) -> float:
        """Share of the skin texels that show the sender's image."""
        return float(self.baked.coverage.sum() / max(int(self.baked.skin.sum()), 1))


def _where(source: str | None, texture: TextureImage | None = None) -> str:
    base = source or "FDP"
    return f"{base}: texture {texture.name!r}" if texture is not None else base


def decode_texture(texture: TextureImage, *, source: str | None = None) -> np.ndarray:
    """An FDP texture's encoded bytes as an (H, W, 3) uint8 RGB image."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(io.BytesIO(texture.data)) as img:
            rgb = image_rgb(img)  # the stored pixels: the texture coordinates name them
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise RenderError(f"the {texture.media_type} image cannot be decoded ({exc})", where=_where(source, texture),
                          hint="send the texture as a complete PNG or JPEG file") from None
    if rgb.shape[0] < 2 or rgb.shape[1] < 2:
        raise RenderError(f"the image is only {rgb.shape[1]}x{rgb.shape[0]} pixels", where=_where(source, texture))
    return rgb


def texture_map(mesh: HeadMesh, fdp: Fdp, size: tuple[int, int], *, source: str | None = None) -> TextureMap:
    """The map from 3D points of ``mesh`` into the image of ``fdp``'s texture coordinates (``size`` its w, h)."""
    where = _where(source, fdp.textures[0] if fdp.textures else None)
    if fdp.texture_coords is None:
        raise RenderError("the FDP carries a texture but no texture coordinates for its feature points", where=where,
                          hint="send the points' texture coordinates (TXCO) with the image, or play without it "
                               "(--no-fdp-texture; fdp_texture=False in the API)")
    labels = tuple(label for label in fdp.labels if label in mesh.fp_labels)
    if len(labels) < MIN_CONTROLS:
        raise RenderError(f"{len(labels)} feature point(s) with texture coordinates; at least {MIN_CONTROLS} are "
                          "needed to map the texture", where=where,
                          hint="send the eyes, nose, mouth and chin points, e.g. 3.5 3.6 9.3 8.3 8.4 2.1")
    controls = np.array([mesh.fp(label) for label in labels])
    uv = np.asarray(fdp.texture_coords, float)[[fdp.index(label) for label in labels]]
    try:
        field = RbfField(controls, uv)
    except FaceError as exc:
        raise RenderError(f"the texture cannot be mapped through the feature points ({exc.message})", where=where,
                          hint="the points must not all lie in one plane, nor two on one spot") from None
    width, height = size
    pix = np.c_[uv[:, 0] * width, (1.0 - uv[:, 1]) * height]
    affine, *_ = np.linalg.lstsq(np.c_[controls, np.ones(len(controls))], pix, rcond=None)
    across, down = affine[:3, 0], affine[:3, 1]
    toward = np.cross(down, across)          # y down x x right: toward the camera (right-handed)
    length = float(np.linalg.norm(toward))
    scale = (float(np.linalg.norm(across)), float(np.linalg.norm(down)))
    if length <= 1e-9 * max(scale) ** 2:
        raise RenderError("the feature points' texture coordinates lie on one line", where=where,
                          hint="texture coordinates must spread across the image as the points do on the face")
    toward = toward / length
    if toward[2] <= 0.0:
        raise RenderError("the texture coordinates show the face from behind: its left side (+x) is on the image's "
                          "left", where=where, hint="check for a mirrored image or swapped left/right labels")
    residual = float(np.sqrt(np.mean(np.sum((np.c_[controls, np.ones(len(controls))] @ affine - pix) ** 2, axis=1))))
    return TextureMap(field=field, size=(int(width), int(height)), labels=labels, toward=toward, scale=scale,
                      residual=residual)


def bake_fdp_texture(mesh: HeadMesh, fdp: Fdp, *, size: int = 1024, source: str | None = None) -> FdpTexture:
    """Bake ``fdp``'s first texture onto the skin of ``mesh`` (the head calibrated to ``fdp``, neutral).

    ``source`` (e.g. the FDP's file name) prefixes the location of errors.
    """
    if not fdp.textures:
        raise RenderError("the FDP carries no texture image", where=_where(source),
                          hint="build it with a front photo (encode --front ...), or give --texture")
    texture = fdp.textures[0]
    image = decode_texture(texture, source=source)
    height, width = image.shape[:2]
    tmap = texture_map(mesh, fdp, (width, height), source=source)
    vertices = np.asarray(mesh.vertices, float)
    projected = tmap.project(vertices)
    raster = uv_rasterise(mesh, size)
    _, points, normals = skin_texels(raster)
    dmap = projected_depth_map(mesh, projected, (width, height))
    head_size = float(np.ptp(vertices[mesh.part("skin")], axis=0).max())
    texel_xy = tmap.project(points)
    colours, seen = sample_projected(image, texel_xy, normals @ tmap.toward, dmap, tmap.scale,
                                     0.005 * head_size)
    baked = assemble(raster, colours, seen, np.where(seen, 1.0, 0.0))
    uv = np.c_[projected[:, 0] / width, 1.0 - projected[:, 1] / height]
    return FdpTexture(baked=baked, map=tmap, vertex_coords=uv, name=texture.name)


def fdp_skin_texture(mesh: HeadMesh, fdp: Fdp | None, *, size: int = 1024,
                     source: str | None = None) -> FdpTexture | None:
    """The FDP's texture baked onto ``mesh`` when it carries one, else None (playback's automatic case)."""
    if fdp is None or not fdp.textures:
        return None
    return bake_fdp_texture(mesh, fdp, size=size, source=source)
