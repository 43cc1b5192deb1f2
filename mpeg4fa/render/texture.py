"""Photo textures for the skin: a front photo (and a side photo) baked into the skin's UV image.

>>> front = PhotoView(image, {"3.5": (212.0, 260.5), "3.6": (300.0, 258.0), "2.1": (255.0, 420.0)}, "front")
>>> baked = bake_texture(face.mesh, front, side, size=1024)
>>> Renderer(face, texture=baked.image)

The method is the seed paper's section 5, in five steps:

1. **UV raster** (:func:`uv_rasterise`): the skin is drawn with GL in texture space
   (``gl_Position`` is the UV) into float32 attachments, so each texel knows the
   3D point and normal it shows. Texels off the skin copy their nearest skin texel
   (unbounded dilation): every mip level then averages skin colours only, and
   bilinear lookups across UV seams and island borders find no background.
2. **Alignment** (:class:`Alignment`): a photo is taken as an orthographic view.
   Per image axis, the bounding box of the annotated feature points on the head
   (front: x-y; side: z-y) maps onto the bounding box of the same points in the
   photo (scale + offset); when one axis is degenerate (all points on a line)
   it borrows the other axis's scale. Directions are those of a real camera:
   in the front photo the face's left (+x) is on the image's right; a ``"left"``
   photo is taken from the face's left side, so the nose points to the image's
   left; a ``"right"`` photo is its mirror image, the nose pointing right.
3. **Sampling**: each texel is projected into each photo and sampled bilinearly.
   A texel counts as seen by a photo when it faces that camera, is not hidden
   (tested against a depth map of the whole head, eyes and teeth included,
   drawn in that photo's frame, with a tolerance that grows with the slope) and
   lands at least a pixel inside the head's outline (so the photo's background
   does not bleed in at the silhouette).
4. **Blend**: ``C = k C_front + (1 - k) C_side`` with ``k = |Nz| / (|Nx| + |Nz|)``.
   The side photo shows one side; a texel on the other side takes the colour of
   its mirror point (x -> -x: the head is symmetric). A texel only one photo sees
   takes that photo's colour; with no side photo, ``k = 1`` wherever the front
   sees the texel.
5. **Fill**: a texel no photo sees whose mirror image (x -> -x) one saw takes that
   colour (a turned face's far cheek wears its near one, :data:`MIRROR_TOLERANCE`);
   the rest (back of the head in front-only mode, inside
   the nostrils, behind the eyeballs) get the mean colour of the covered skin
   near them in 3D (a Gaussian-weighted mean over a few centimetres), drawn toward
   the overall mean of the covered skin where little covered skin is near.

Point coordinates follow :meth:`.camera.Camera.project`: x right, y down, origin
at the image's top-left corner, pixel centres at +0.5 (integer pixel indices
from an image viewer are half a pixel off, which does not matter).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
from scipy import ndimage

from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.render.context import gl_context, program
from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.scene import vertex_normals

__all__ = ["PhotoView", "BakedTexture", "Alignment", "UVRaster", "bake_texture", "uv_rasterise", "align_view",
           "projected_depth_map", "sample_projected", "skin_texels", "assemble"]

VIEWS = ("front", "left", "right")
SIDE_VIEWS = ("left", "right")

VIEW_AXES: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "front": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    "left": ((0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),
    "right": ((0.0, 0.0, 1.0), (-1.0, 0.0, 0.0)),
}
"""Per view: the head axis that points to the image's right, and the one toward the camera."""
_DRAWN_PARTS = ("skin", "eye_l", "eye_r", "teeth_upper", "teeth_lower", "tongue")
DEPTH_MAP_SIZE = 1024      # long side of the visibility depth maps, in pixels
MIN_SIZE, MAX_SIZE = 16, 8192



# -- inputs ----------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class PhotoView:
    """A photo of the head and its annotated feature points.

    ``points`` maps feature point labels ("3.5", "9.3", ...) to pixel coordinates
    (x right, y down); ``view`` says where the camera stood: ``"front"``, or
    ``"left"`` / ``"right"`` for a photo of the face's left / right side.
    """

    image: np.ndarray
    points: Mapping[str, tuple[float, float]]
    view: str = "front"

    def __post_init__(self) -> None:
        img = self.image
        if not isinstance(img, np.ndarray) or img.ndim != 3 or img.shape[2] != 3 or img.dtype != np.uint8:
            what = (f"{img.dtype} array of shape {img.shape}" if isinstance(img, np.ndarray)
                    else type(img).__name__)
            raise RenderError(f"a photo must be an (H, W, 3) uint8 RGB array, got a {what}", where="photo",
                              hint="convert it, e.g. np.asarray(PIL.Image.open(path).convert('RGB'))")
        if img.shape[0] < 2 or img.shape[1] < 2:
            raise RenderError(f"the photo is only {img.shape[1]}x{img.shape[0]} pixels", where="photo")
        if self.view not in VIEWS:
            raise RenderError(f"unknown photo view {self.view!r}", where="photo",
                              hint="'front', or 'left' / 'right' for a photo of the face's left / right side")
        points: dict[str, tuple[float, float]] = {}
        for label, xy in dict(self.points).items():
            p = np.asarray(xy, float)
            if p.shape != (2,) or not np.all(np.isfinite(p)):
                raise RenderError(f"feature point {label!r} is {xy!r}", where=f"{self.view} photo",
                                  hint="give each label one finite (x, y) pixel position")
            points[str(label)] = (float(p[0]), float(p[1]))
        object.__setattr__(self, "points", points)


# -- results ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class Alignment:
    """How the head maps into one photo: an orthographic projection, scale + offset per image axis.

    ``scale`` is pixels per mm across and up; ``offset`` the pixel position of the
    head's origin; ``residual`` the RMS distance (pixels) between the annotated
    points and the head's feature points mapped into the photo: large values mean
    a misplaced label or a head whose proportions differ from the photo's.
    """

    view: str
    scale: tuple[float, float]
    offset: tuple[float, float]
    labels: tuple[str, ...]
    residual: float

    def project(self, points: np.ndarray) -> np.ndarray:
        """(N, 3): photo x, y (pixels) and depth toward the camera (mm, larger = nearer)."""
        p = np.asarray(points, float)
        across, toward = (np.asarray(a) for a in VIEW_AXES[self.view])
        x = self.scale[0] * (p @ across) + self.offset[0]
        y = self.offset[1] - self.scale[1] * p[:, 1]
        return np.c_[x, y, p @ toward]


@dataclass(frozen=True, eq=False)
class UVRaster:
    """The skin in texture space, row 0 = v 1 like the texture image.

    Off the skin (``skin`` False) a texel holds the position and normal of the
    skin texel it copies (``nearest``, a flat index; a skin texel is its own).
    """

    position: np.ndarray  # (S, S, 3) float32, mm
    normal: np.ndarray    # (S, S, 3) float32, unit length
    skin: np.ndarray      # (S, S) bool
    nearest: np.ndarray   # (S, S) int64

    @property
    def size(self) -> int:
        return self.skin.shape[0]


@dataclass(frozen=True, eq=False)
class BakedTexture:
    """A baked skin texture and how it came about.

    ``image`` is ready for ``Renderer(texture=...)``; ``coverage`` marks skin texels
    that got a photo colour (the others were filled); ``weight_front`` is the share
    of the front photo in each covered texel (0 off the coverage).
    """

    image: np.ndarray         # (S, S, 3) uint8, row 0 = v 1
    coverage: np.ndarray      # (S, S) bool
    weight_front: np.ndarray  # (S, S) float32
    skin: np.ndarray          # (S, S) bool, texels on the skin's UV islands
    alignments: dict[str, Alignment] = field(default_factory=dict)


# -- GL helpers ------------------------------------------------------------------------------

# -- step 1: the skin in UV space ------------------------------------------------------------

def uv_rasterise(mesh: HeadMesh, size: int = 1024, vertices: np.ndarray | None = None) -> UVRaster:
    """Each texel's 3D point and normal on the skin (of ``vertices``, default the neutral mesh).

    Texels off the skin copy their nearest skin texel, so anything computed per
    texel from the raster is dilated across UV seams and borders for free.
    """
    size = _check_size(size)
    verts = np.asarray(mesh.vertices if vertices is None else vertices, float)
    tri = np.asarray(mesh.triangles["skin"], np.int64)
    uv = np.asarray(mesh.corner_uvs["skin"], np.float64).reshape(-1, 2)
    normals = vertex_normals(verts, tri)
    data = np.c_[verts[tri.reshape(-1)], normals[tri.reshape(-1)], uv].astype(np.float32)

    ctx = gl_context()
    prog = program("uv_bake")
    targets = [ctx.texture((size, size), 4, dtype="f4") for _ in range(2)]
    fbo = ctx.framebuffer(color_attachments=targets)
    vbo = ctx.buffer(data.tobytes())
    vao = ctx.vertex_array(prog, [(vbo, "3f 3f 2f", "in_position", "in_normal", "in_uv")])
    try:
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        ctx.disable(ctx.DEPTH_TEST | ctx.CULL_FACE | ctx.BLEND)
        vao.render()
        read = [np.frombuffer(fbo.read(components=4, attachment=i, dtype="f4"), np.float32)
                .reshape(size, size, 4)[::-1] for i in range(2)]
    finally:
        for obj in (vao, vbo, fbo, *targets):
            obj.release()

    skin = read[0][..., 3] > 0.5
    if not skin.any():
        raise RenderError("the skin covers no texel of the UV image", where="texture bake",
                          hint="the mesh's skin UVs must lie in [0, 1]")
    _, (rows, cols) = ndimage.distance_transform_edt(~skin, return_indices=True)
    nearest = (rows * size + cols).astype(np.int64)
    position = read[0][..., :3].reshape(-1, 3)[nearest]
    normal = read[1][..., :3].reshape(-1, 3)[nearest]
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    normal = normal / np.where(length > 0, length, 1.0)
    return UVRaster(position=position, normal=normal.astype(np.float32), skin=skin, nearest=nearest)


def _check_size(size: int) -> int:
    if not (MIN_SIZE <= int(size) <= MAX_SIZE):
        raise RenderError(f"texture size {size} is out of range", where="texture bake",
                          hint=f"{MIN_SIZE} to {MAX_SIZE} texels (1024 is plenty for a head)")
    return int(size)


# -- step 2: alignment -----------------------------------------------------------------------

def align_view(mesh: HeadMesh, photo: PhotoView) -> Alignment:
    """Map the head into ``photo`` by the bounding boxes of its annotated feature points."""
    where = f"{photo.view} photo"
    unknown = sorted(set(photo.points) - set(mesh.fp_labels))
    if unknown:
        raise RenderError(f"labels {', '.join(unknown)} are not feature points of this head", where=where,
                          hint="use MPEG-4 labels such as 3.5 (left pupil), 9.3 (nose tip), 2.1 (chin)")
    labels = tuple(photo.points)
    if len(labels) < 2:
        raise RenderError(f"{len(labels)} annotated feature point(s); at least 2 are needed", where=where,
                          hint="annotate e.g. the pupils 3.5/3.6, the nose tip 9.3 and the chin 2.1")
    across, _ = (np.asarray(a) for a in VIEW_AXES[photo.view])
    head3 = np.array([mesh.fp(label) for label in labels])
    head = np.c_[head3 @ across, head3[:, 1]]        # across (to the image's right), up
    pix = np.array([photo.points[label] for label in labels])
    pix = np.c_[pix[:, 0], -pix[:, 1]]               # both axes now grow the same way as the head's
    head_ext = np.ptp(head, axis=0)
    pix_ext = np.ptp(pix, axis=0)
    head_size = float(np.ptp(mesh.vertices[mesh.part("skin")], axis=0).max())
    usable = (head_ext > 1e-3 * head_size) & (pix_ext > 0.5)
    if not usable.any():
        raise RenderError("the annotated points span no distance on the head or in the photo", where=where,
                          hint="annotate points that lie apart both on the face and in the photo")
    names = ("across the image", "up the image")
    for axis in np.flatnonzero(usable):
        corr = np.dot(head[:, axis] - head[:, axis].mean(), pix[:, axis] - pix[:, axis].mean())
        if corr < 0:
            what = ("the face's left side should be on the image's right" if photo.view == "front" else
                    f"in a {photo.view!r} photo the nose should point to the image's "
                    f"{'left' if photo.view == 'left' else 'right'}")
            raise RenderError(f"the annotated points run the wrong way {names[axis]}: {what}", where=where,
                              hint="check for swapped left/right labels, a mirrored photo or the wrong view name")
    scale = np.where(usable, pix_ext / np.where(usable, head_ext, 1.0), 0.0)
    scale[~usable] = scale[usable][0]
    centre_head = (head.min(axis=0) + head.max(axis=0)) / 2.0
    centre_pix = (pix.min(axis=0) + pix.max(axis=0)) / 2.0
    off = centre_pix - scale * centre_head
    mapped = head * scale + off
    residual = float(np.sqrt(np.mean(np.sum((mapped - pix) ** 2, axis=1))))
    return Alignment(view=photo.view, scale=(float(scale[0]), float(scale[1])),
                     offset=(float(off[0]), float(-off[1])), labels=labels, residual=residual)


# -- step 3: sampling with visibility ---------------------------------------------------------

@dataclass(frozen=True, eq=False)
class DepthMap:
    depth: np.ndarray   # (h, w) float32, toward the camera, mm
    solid: np.ndarray   # (h, w) bool: the head covers the pixel and its neighbours
    photo_size: tuple[int, int]  # photo (width, height)


def _depth_map(mesh: HeadMesh, vertices: np.ndarray, align: Alignment, photo_size: tuple[int, int]) -> DepthMap:
    """The head drawn in the photo's frame (at most DEPTH_MAP_SIZE pixels a side) for occlusion tests."""
    return projected_depth_map(mesh, align.project(vertices), photo_size)


def projected_depth_map(mesh: HeadMesh, projected: np.ndarray, photo_size: tuple[int, int]) -> DepthMap:
    """The head drawn from vertices already mapped into a photo: (V, 3) pixel x, y and depth (mm, larger = nearer).

    Any map into the photo will do (an orthographic view, or a warp interpolated
    from texture coordinates): occlusion is decided where each surface lands.
    """
    width, height = photo_size
    f = DEPTH_MAP_SIZE / max(width, height)
    w, h = max(int(round(width * f)), 2), max(int(round(height * f)), 2)
    proj = np.asarray(projected, float)
    depth = proj[:, 2]
    mid, half = (depth.max() + depth.min()) / 2.0, (np.ptp(depth) / 2.0) * 1.05 + 1.0
    m = np.zeros((4, 4))      # pixels -> clip: x right, y down, nearer = smaller GL depth
    m[0, 0], m[0, 3] = 2.0 / width, -1.0
    m[1, 1], m[1, 3] = -2.0 / height, 1.0
    m[2, 2], m[2, 3] = -1.0 / half, mid / half
    m[3, 3] = 1.0

    ctx = gl_context()
    prog = program("depth_view")
    prog["world_to_clip"].write(m.T.astype(np.float32).tobytes())
    prog["toward_camera"].value = (0.0, 0.0, 1.0)
    tri = mesh.all_triangles(_DRAWN_PARTS).astype(np.uint32)
    target = ctx.texture((w, h), 4, dtype="f4")
    fbo = ctx.framebuffer(color_attachments=[target], depth_attachment=ctx.depth_renderbuffer((w, h)))
    vbo = ctx.buffer(proj.astype(np.float32).tobytes())
    ibo = ctx.buffer(tri.tobytes())
    vao = ctx.vertex_array(prog, [(vbo, "3f", "in_position")], index_buffer=ibo, index_element_size=4)
    try:
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE | ctx.BLEND)
        vao.render()
        img = np.frombuffer(fbo.read(components=4, dtype="f4"), np.float32).reshape(h, w, 4)[::-1]
    finally:
        for obj in (vao, ibo, vbo, fbo, target):
            obj.release()
    covered = img[..., 1] > 0.5
    # keep samples a photo pixel inside the outline: a bilinear tap there sees no background
    steps = max(1, int(np.ceil(w / width)))
    solid = ndimage.binary_erosion(covered, np.ones((3, 3), bool), iterations=steps, border_value=0)
    return DepthMap(depth=np.ascontiguousarray(img[..., 0]), solid=solid, photo_size=(width, height))


def _bilinear(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Colours (N, 3) float32 of an (H, W, 3) image at pixel coordinates (centres at +0.5), edges clamped."""
    h, w = image.shape[:2]
    fx = np.clip(x - 0.5, 0.0, w - 1.0)
    fy = np.clip(y - 0.5, 0.0, h - 1.0)
    x0 = np.minimum(fx.astype(np.int64), w - 2)   # photos are at least 2x2 (PhotoView checks)
    y0 = np.minimum(fy.astype(np.int64), h - 2)
    tx = (fx - x0).astype(np.float32)[:, None]
    ty = (fy - y0).astype(np.float32)[:, None]
    flat = image.reshape(-1, 3)
    i00 = y0 * w + x0
    c00, c01 = flat[i00].astype(np.float32), flat[i00 + 1].astype(np.float32)
    c10, c11 = flat[i00 + w].astype(np.float32), flat[i00 + w + 1].astype(np.float32)
    top = c00 + (c01 - c00) * tx
    bottom = c10 + (c11 - c10) * tx
    return top + (bottom - top) * ty


def _sample_view(photo: PhotoView, align: Alignment, dmap: DepthMap, points: np.ndarray, normals: np.ndarray,
                 tolerance_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(colours (N, 3) float32, seen (N,) bool) of surface points in one photo."""
    _, toward = (np.asarray(a) for a in VIEW_AXES[align.view])
    return sample_projected(photo.image, align.project(points), normals @ toward, dmap,
                            align.scale, tolerance_mm)


def sample_projected(image: np.ndarray, projected: np.ndarray, facing: np.ndarray, dmap: DepthMap,
                     scale: tuple[float, float], tolerance_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(colours (N, 3) float32, seen (N,) bool) of surface points mapped into a photo.

    ``projected`` is (N, 3) pixel x, y and depth toward the camera; ``facing`` the
    cosine between each point's normal and the direction toward the camera;
    ``scale`` the photo's pixels per mm across and up (for the depth tolerance).
    """
    width, height = dmap.photo_size
    x, y, d = projected[:, 0], projected[:, 1], projected[:, 2]
    inside = (x >= 0) & (x < width) & (y >= 0) & (y < height) & (facing > 0)
    h, w = dmap.depth.shape
    col = np.clip((x * (w / width)).astype(np.int64), 0, w - 1)
    row = np.clip((y * (h / height)).astype(np.int64), 0, h - 1)
    # a depth pixel spans this many mm; a slanted surface's depth varies across it by its slope
    pixel_mm = max(width / w / scale[0], height / h / scale[1])
    slope = np.sqrt(np.maximum(1.0 - facing ** 2, 0.0)) / np.maximum(facing, 1e-3)
    tol = tolerance_mm + pixel_mm * (1.0 + np.minimum(slope, 8.0))
    seen = inside & dmap.solid[row, col] & (d >= dmap.depth[row, col] - tol)
    colours = np.zeros((len(projected), 3), np.float32)
    colours[seen] = _bilinear(image, x[seen], y[seen])
    return colours, seen


# -- steps 4 and 5: blend, fill, assemble ----------------------------------------------------

def _fill_unseen(points: np.ndarray, colours: np.ndarray, seen: np.ndarray) -> np.ndarray:
    """Colours for unseen points: the Gaussian-weighted mean of seen points near them in 3D.

    Sums and counts of the seen points are splatted on a coarse grid and blurred
    (a normalised convolution); where little seen skin is near, the estimate is
    drawn toward the mean of all seen points.
    """
    out = colours.copy()
    unseen = ~seen
    if not unseen.any():
        return out
    if not seen.any():
        out[:] = 128.0
        return out
    lo, hi = points.min(axis=0), points.max(axis=0)
    cell = float((hi - lo).max()) / 32.0 + 1e-6
    shape = tuple(int(n) for n in np.floor((hi - lo) / cell).astype(int) + 1)
    idx = np.floor((points[seen] - lo) / cell).astype(np.int64)
    flat = np.ravel_multi_index(idx.T, shape)
    n_cells = int(np.prod(shape))
    grids = [np.bincount(flat, minlength=n_cells).astype(np.float64)]
    grids += [np.bincount(flat, colours[seen, c], minlength=n_cells) for c in range(3)]
    blurred = [ndimage.gaussian_filter(g.reshape(shape), sigma=1.5, mode="constant") for g in grids]
    coords = ((points[unseen] - lo) / cell - 0.5).T   # cell centres sit at +0.5
    values = [ndimage.map_coordinates(b, coords, order=1, mode="nearest") for b in blurred]
    prior = 0.02 * blurred[0].max()
    mean = colours[seen].mean(axis=0)
    for c in range(3):
        out[unseen, c] = (values[c + 1] + prior * mean[c]) / (values[0] + prior)
    return out


MIRROR_TOLERANCE = 0.01
"""How far (a share of the head's size) an unseen texel's mirror image may lie from the nearest seen texel
and still take its colour: the head is symmetric, not exactly so once calibrated."""

MIRROR_MARGIN = 0.03
"""Seen texels nearer than this (a share of the head's size) to an unseen one are not copied to the other side."""


def _mirror_unseen(points: np.ndarray, colours: np.ndarray, seen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(colours, mirrored): unseen texels whose mirror image (x -> -x) a photo saw take that colour.

    One front photo of a turned face sees one cheek well and the other barely; the far side then
    wears the near side's skin rather than a blur of the seen skin around it.
    """
    mirrored = np.zeros(len(points), bool)
    unseen = np.flatnonzero(~seen)
    if not len(unseen) or not seen.any():
        return colours, mirrored
    from scipy.spatial import cKDTree

    size = float(np.ptp(points, axis=0).max())
    tolerance = MIRROR_TOLERANCE * size
    # sources: seen texels away from the edge of what was seen (the edge is seen at a grazing angle, often
    # with the photo's background or hair in it; copied, it would draw a line on the other side)
    edge, _ = cKDTree(points[unseen]).query(points[seen], distance_upper_bound=MIRROR_MARGIN * size)
    source = np.flatnonzero(seen)[~np.isfinite(edge)]
    if not len(source):
        return colours, mirrored
    distance, index = cKDTree(points[source]).query(points[unseen] * [-1.0, 1.0, 1.0],
                                                     distance_upper_bound=tolerance)
    hit = np.isfinite(distance)
    out = colours.copy()
    out[unseen[hit]] = colours[source[index[hit]]]
    mirrored[unseen[hit]] = True
    return out, mirrored


def bake_texture(mesh: HeadMesh, front: PhotoView, side: PhotoView | None = None, *,
                 size: int = 1024) -> BakedTexture:
    """Texture the skin of ``mesh`` (its neutral vertices) from a front photo and an optional side photo."""
    if not isinstance(front, PhotoView) or front.view != "front":
        raise RenderError("the first photo must be a PhotoView with view='front'", where="texture bake",
                          hint="PhotoView(image, points, 'front')")
    if side is not None and (not isinstance(side, PhotoView) or side.view not in SIDE_VIEWS):
        raise RenderError("the side photo must be a PhotoView with view 'left' or 'right'", where="texture bake",
                          hint="'left' for a photo of the face's left side (nose toward the image's left)")
    size = _check_size(size)
    raster = uv_rasterise(mesh, size)
    vertices = np.asarray(mesh.vertices, float)
    _, points, normals = skin_texels(raster)
    head_size = float(np.ptp(vertices[mesh.part("skin")], axis=0).max())
    tolerance = 0.005 * head_size

    photos = {"front": front} if side is None else {"front": front, side.view: side}
    alignments = {view: align_view(mesh, photo) for view, photo in photos.items()}
    maps = {view: _depth_map(mesh, vertices, alignments[view], (photo.image.shape[1], photo.image.shape[0]))
            for view, photo in photos.items()}

    c_front, seen_front = _sample_view(front, alignments["front"], maps["front"], points, normals, tolerance)
    k = np.where(seen_front, 1.0, 0.0)
    colours = c_front
    seen = seen_front
    if side is not None:
        # the side photo shows one side; points on the other side are read at their mirror image
        sign = 1.0 if side.view == "left" else -1.0
        flip = points[:, 0] * sign < 0
        mirror = np.where(flip[:, None], [-1.0, 1.0, 1.0], 1.0)
        c_side, seen_side = _sample_view(side, alignments[side.view], maps[side.view], points * mirror,
                                         normals * mirror, tolerance)
        nx, nz = np.abs(normals[:, 0]), np.abs(normals[:, 2])
        total = nx + nz
        k_geo = np.where(total > 1e-6, nz / np.maximum(total, 1e-6), 0.5)
        k = np.where(seen_front & seen_side, k_geo, np.where(seen_front, 1.0, 0.0))
        colours = k[:, None] * c_front + (1.0 - k[:, None]) * c_side
        seen = seen_front | seen_side
    return assemble(raster, colours, seen, k, alignments)


def skin_texels(raster: UVRaster) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flat indices of the skin texels, and their 3D points and normals (float64)."""
    skin_idx = np.flatnonzero(raster.skin.reshape(-1))
    points = raster.position.reshape(-1, 3)[skin_idx].astype(np.float64)
    normals = raster.normal.reshape(-1, 3)[skin_idx].astype(np.float64)
    return skin_idx, points, normals


def assemble(raster: UVRaster, colours: np.ndarray, seen: np.ndarray, k: np.ndarray,
             alignments: dict[str, Alignment] | None = None) -> BakedTexture:
    """Per-skin-texel colours (unseen ones filled here) spread over the whole UV image.

    Unseen texels take their mirror image's colour where a photo saw it, else a fill from the seen
    skin near them. Off-skin texels repeat their nearest skin texel, across seams and island
    borders, so mip-maps and bilinear lookups never see a background colour.
    """
    size = raster.size
    skin_idx, points, _ = skin_texels(raster)
    colours, mirrored = _mirror_unseen(points, colours, seen)
    colours = _fill_unseen(points, colours, seen | mirrored)
    per_texel = np.zeros((size * size, 3), np.float32)
    per_texel[skin_idx] = colours
    image = np.clip(np.rint(per_texel[raster.nearest.reshape(-1)]), 0, 255).astype(np.uint8)
    coverage = np.zeros(size * size, bool)
    coverage[skin_idx] = seen
    weight = np.zeros(size * size, np.float32)
    weight[skin_idx] = np.where(seen, k, 0.0)
    return BakedTexture(image=image.reshape(size, size, 3), coverage=coverage.reshape(size, size),
                        weight_front=weight.reshape(size, size), skin=raster.skin, alignments=dict(alignments or {}))
