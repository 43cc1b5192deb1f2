"""Pixels from poses: an offscreen framebuffer, the face shaders, and readback into arrays.

>>> renderer = Renderer(face, width=512, height=512)
>>> image = renderer.render(face.deform({3: 400}))      # (512, 512, 3) uint8, top row first

One renderer owns its framebuffer and GPU buffers; the GL context is shared
(:mod:`.context`). ``samples`` > 0 draws into a multisampled framebuffer and
resolves it (anti-aliasing for final output). Geometry is uploaded per frame:
only positions and normals change, so the layout (:mod:`.scene`) is built once.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from mpeg4fa.face.eyes import eye_looks
from mpeg4fa.face.looks import nose_wrinkle, points_of
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.model import FaceModel
from mpeg4fa.limits import SAMPLES, LimitError
from mpeg4fa.render.brows import ALONG, HEIGHT, about_the_brows, brow_hair_image
from mpeg4fa.render.camera import Camera, frame_points
from mpeg4fa.render.context import gl_context, program
from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.iris import IRIS_SCALE, iris_pattern
from mpeg4fa.render.lashes import build_lashes, lash_vertices
from mpeg4fa.render.materials import PART_MATERIAL, TEETH, Materials
from mpeg4fa.render.refine import interpolated, mouth_patch, refine, refined_vertices
from mpeg4fa.render.scene import build_layout, vertex_data

_EYES = (("eye_l", "l-eye"), ("eye_r", "r-eye"))
MAX_SIZE = 8192
EYE_ALBEDO_SIZE = 512
"""Texels a side of the baked eyeball (its map runs from the front pole down to the back: the iris takes the first
sixth, some 80 texels from the pupil's centre to the limbus)."""
TEETH_ALBEDO_SIZE = 1024
"""Texels a side of the teeth's own baked image, over their islands' box in the UV square: on the generic head a median
8.6-9.4 texels a mm along the teeth's edges (in the skin's 2048 image about 1, so a gap between two teeth was a
texel; 86 KiB of PNG)."""
BAKED_WITH_SKIN = ("teeth_upper", "teeth_lower", "tongue")
"""Parts :meth:`Renderer.albedo` bakes into the skin's UV image where their UVs lie apart from it (the generic head's
map keeps them in free corners of the skin's square)."""
OVERLAP_SHARE = 0.05
"""A part baked with the skin may share at most this share of its texels with what is baked already (the generic
head's upper and lower teeth touch along a row of texels; a part laid over another shares most of them)."""
STATIC_ATTRIBUTES = ("2f 1f 2f 2f 2f 1f", "in_uv", "in_material", "in_tints", "in_detail", "in_nose", "in_neck")
"""The layout's per-vertex columns (uv, material, lips and cavity tints, detail, nose, neck) as the face programs read them."""

KEY_LIGHT = ((-0.45, 0.45, 0.77), (0.78, 0.76, 0.72))
FILL_LIGHT = ((0.65, 0.05, 0.75), (0.28, 0.30, 0.34))
AMBIENT = (0.24, 0.24, 0.26)


class Albedo(NamedTuple):
    """What :meth:`Renderer.albedo` bakes: the UV image, the parts whose colours it holds, the left eyeball's own UV
    image (sclera, iris, pupil; None without eyes), which the right one's map shares on the generic head, and the
    teeth's own image over their islands' box (None without teeth)."""

    image: np.ndarray
    parts: tuple[str, ...]
    eye: np.ndarray | None = None
    owner: np.ndarray | None = None  # (H, W) uint8, top row first: each texel's part (index into parts; 255: none)
    teeth: np.ndarray | None = None  # the teeth's own image over ``teeth_frame`` of the UV square (None: no teeth)
    teeth_frame: tuple[float, float, float, float] | None = None  # (u, v origin, u, v span)


class _Uniforms:
    """Sets a uniform on each of the program variants that has it (bytes are written, values assigned)."""

    def __init__(self, programs) -> None:
        self.programs = programs

    def __setitem__(self, name: str, value) -> None:
        for prog in self.programs:
            if name in prog:
                if isinstance(value, bytes):
                    prog[name].write(value)
                else:
                    prog[name].value = value


def _filled(rgba: np.ndarray) -> np.ndarray:
    """An (H, W, 4) bake, bottom row first, as an (H, W, 3) image top row first whose texels off every island (alpha
    0) take their nearest island texel's colour."""
    from scipy import ndimage

    rgba = rgba[::-1]
    covered = rgba[..., 3] > 0
    nearest = ndimage.distance_transform_edt(~covered, return_distances=False, return_indices=True)
    return np.ascontiguousarray(rgba[..., :3][nearest[0], nearest[1]])


def _without(cut: tuple[int, int], ranges: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """``ranges`` ((first, count) of the index buffer) less the range ``cut``, which lies within one of them."""
    start, end = cut[0], cut[0] + cut[1]
    out = []
    for first, count in ranges:
        last = first + count
        if end <= first or start >= last or start == end:
            out.append((first, count))
        else:
            out += [r for r in ((first, start - first), (end, last - end)) if r[1] > 0]
    return out


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


class Renderer:
    """Draws one face (its mesh layout, materials and framing) into an offscreen image."""

    def __init__(self, face: FaceModel, *, width: int = 512, height: int = 512, samples: int = 0,
                 camera: Camera | None = None, view: str | tuple[float, float] = "front",
                 materials: Materials | None = None, texture: np.ndarray | None = None,
                 lighting: bool = True, key_light: tuple[float, float, float] | None = None,
                 lashes: bool = True) -> None:
        """``key_light``: the main light's direction (toward the light, head frame; default upper left front);
        ``lashes=False`` leaves the lash cards out (the eyeball alone, e.g. to measure the pupils)."""
        if not (1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE):
            raise RenderError(f"image size {width}x{height} is out of range", where="renderer",
                              hint=f"width and height from 1 to {MAX_SIZE}")
        self.face = face
        self.width, self.height = int(width), int(height)
        self.materials = materials or Materials()
        self.lighting = lighting
        self._baking = False  # drawing the head's own colours into its UV image (albedo)
        self.key_light = _unit(KEY_LIGHT[0] if key_light is None else key_light)
        self.layout = build_layout(face.mesh)
        self.lashes = build_lashes(face.mesh) if lashes else None
        self.camera = camera or frame_points(face.mesh.feature_points(), self.width, self.height, view=view)
        self.ctx = gl_context()
        self._setup_gl(samples)
        self.set_texture(texture)
        # 8-bit, llvmpipe's fast path
        pattern = np.round(np.clip(iris_pattern() / IRIS_SCALE, 0.0, 1.0) * 255).astype(np.uint8)
        self.iris_texture = self.ctx.texture((pattern.shape[1], pattern.shape[0]), 4,
                                             np.dstack([pattern, np.full(pattern.shape[:2], 255, np.uint8)]).tobytes())
        self.iris_texture.repeat_x, self.iris_texture.repeat_y = True, False
        hairs = brow_hair_image()  # RGBA8 as the iris's: llvmpipe's fast path
        self.brow_texture = self.ctx.texture((hairs.shape[1], hairs.shape[0]), 4,
                                             np.repeat(hairs[..., None], 4, axis=2).tobytes())
        self.brow_texture.repeat_x = self.brow_texture.repeat_y = False
        self.brow_texture.build_mipmaps()  # from afar, the hairs' mean cover
        self._vertex_data = np.empty((self.layout.n_vertices, 6), np.float32)
        self._lash_data = np.empty((self.lashes.n_vertices, 6), np.float32) if self.lashes else None
        self._pixels = np.empty((self.height, self.width, 3), np.uint8)
        self._neutral_points = face.feature_points()

    # -- set-up ----------------------------------------------------------------------------

    def _setup_gl(self, samples: int) -> None:
        ctx = self.ctx
        max_samples = ctx.max_samples
        try:
            samples = SAMPLES.check(samples)
        except LimitError as exc:
            raise RenderError(exc.message, where="renderer", hint=exc.hint) from None
        if samples > max_samples:
            here = ", ".join(str(n) for n in SAMPLES.choices if n <= max_samples)
            raise RenderError(f"{samples} samples for anti-aliasing is more than this GL context allows",
                              where="renderer", hint=f"one of {here}")
        self.samples = int(samples)
        self.program = program("face")  # shared: uniforms are set again before every draw
        self.eye_program = program("face", ("EYES",))
        self.lash_program = program("face", ("LASHES",))
        self.brow_program = program("face", ("BROWS",))
        self.uniforms = _Uniforms((self.program, self.eye_program, self.lash_program, self.brow_program))
        size = (self.width, self.height)
        self.fbo = ctx.framebuffer(ctx.renderbuffer(size, 4), ctx.depth_renderbuffer(size))
        self.ms_fbo = None
        if self.samples:
            self.ms_fbo = ctx.framebuffer(ctx.renderbuffer(size, 4, samples=self.samples),
                                          ctx.depth_renderbuffer(size, samples=self.samples))
        lay = self.layout
        self.dynamic = ctx.buffer(reserve=lay.n_vertices * 6 * 4, dynamic=True)
        static = np.c_[lay.uv, lay.material, lay.lips, lay.cavity, lay.detail, lay.nose, lay.neck].astype(np.float32)
        self.static = ctx.buffer(static.tobytes())
        # the skin's block (build_layout puts the skin first) reordered: the rest of it, then the triangles about the
        # mouth (drawn finer: render/refine.py; the UV bake draws them as they are), then those about the brows (drawn
        # by the brow variant: only they pay for the hairs)
        skin = len(self.face.mesh.triangles.get("skin", ()))
        brows = about_the_brows(lay.detail, lay.indices[:skin])
        mouth = np.zeros(skin, bool)
        mouth[mouth_patch(lay, np.flatnonzero(~brows))] = True
        plain = ~brows & ~mouth
        indices = np.concatenate([lay.indices[:skin][plain], lay.indices[:skin][mouth], lay.indices[:skin][brows],
                                  lay.indices[skin:]])
        self.index = ctx.buffer(indices.astype(np.uint32).tobytes())
        self.mouth_range = (3 * int(plain.sum()), 3 * int(mouth.sum()))
        self.patch = refine(lay, np.flatnonzero(mouth)) if mouth.any() else None
        self.patch_vao = self.patch_buffers = self._patch_data = None
        if self.patch is not None:
            columns = np.c_[lay.uv, lay.material, lay.lips, lay.cavity, lay.detail, lay.nose, lay.neck]
            self._patch_data = np.empty((self.patch.n_points, 6), np.float32)
            self.patch_buffers = (ctx.buffer(reserve=self.patch.n_points * 6 * 4, dynamic=True),
                                  ctx.buffer(interpolated(self.patch, columns).astype(np.float32).tobytes()),
                                  ctx.buffer(self.patch.indices.tobytes()))
            self.patch_vao = self._face_array(self.program, *self.patch_buffers)
        self.vao = self._face_array(self.program)
        self.brow_vao = self._face_array(self.brow_program)
        self.brow_range = (3 * (skin - int(brows.sum())), 3 * int(brows.sum()))
        # the eyes' triangles, one block of the index buffer, are drawn by the eye variant
        eye_slots = [PART_MATERIAL["eye_l"], PART_MATERIAL["eye_r"]]
        is_eye = np.flatnonzero(np.isin(lay.material[indices[:, 0]], eye_slots))
        self.eye_vao = None
        self.face_ranges = _without(self.mouth_range, _without(self.brow_range, [(0, 3 * len(indices))]))
        if len(is_eye) and is_eye[-1] - is_eye[0] + 1 == len(is_eye):
            a, b = 3 * int(is_eye[0]), 3 * (int(is_eye[-1]) + 1)
            self.face_ranges = _without(self.mouth_range,
                                        _without(self.brow_range, [(0, a), (b, 3 * len(indices) - b)]))
            self.eye_range = (a, b - a)
            self.eye_vao = self._face_array(self.eye_program)
        else:  # not one block: everything but the brows by one variant that has the eyes' code
            self.vao.release()
            self.vao = self._face_array(self.eye_program)
        self.lash_vao = self.lash_buffers = None
        if self.lashes is not None:  # a draw of their own: the cards along the lid margins
            lash = self.lashes
            dynamic = ctx.buffer(reserve=lash.n_vertices * 6 * 4, dynamic=True)
            static = ctx.buffer(lash.static.tobytes())
            index = ctx.buffer(lash.indices.tobytes())
            self.lash_buffers = (dynamic, static, index)
            self.lash_vao = ctx.vertex_array(
                self.lash_program, [(dynamic, "3f 3f", "in_position", "in_normal"),
                                    (static, "2f 1f 2f 2f 2f", "in_uv", "in_material", "in_tints", "in_detail",
                                     "in_nose")],
                index_buffer=index, index_element_size=4)

    def _face_array(self, prog, dynamic=None, static=None, index=None):
        """A vertex array of the face program variant ``prog`` over positions + normals (``dynamic``), the
        :data:`STATIC_ATTRIBUTES` (``static``) and triangles (``index``): the head's own buffers unless given."""
        dynamic = self.dynamic if dynamic is None else dynamic
        static = self.static if static is None else static
        index = self.index if index is None else index
        return self.ctx.vertex_array(prog, [(dynamic, "3f 3f", "in_position", "in_normal"),
                                            (static, *STATIC_ATTRIBUTES)], index_buffer=index, index_element_size=4)

    def _apply_uniforms(self) -> None:
        """Materials, lights, camera and texture (the program is shared by all renderers)."""
        m, prog = self.materials, self.uniforms
        slots = [m.skin, m.mouth, m.sclera, m.teeth, m.tongue, m.gums]
        prog["base_colour"] = np.array([s.colour for s in slots], np.float32).tobytes()
        prog["shine"] = np.array([(s.specular, s.shininess) for s in slots], np.float32).tobytes()
        prog["lip_colour"] = tuple(m.lips)
        prog["brow_colour"] = tuple(m.brows)
        prog["brow_frame"] = (ALONG[0], HEIGHT[0], ALONG[1] - ALONG[0], HEIGHT[1] - HEIGHT[0])
        prog["cavity_colour"] = tuple(m.cavity)
        prog["iris_colour"] = tuple(m.iris)
        prog["pupil_colour"] = tuple(m.pupil)
        prog["lash_colour"] = tuple(m.lashes)
        looks = eye_looks()
        prog["cornea_radius"] = looks.cornea_radius
        prog["wet"] = (looks.wet_specular, looks.wet_shininess)
        prog["lash_strands"] = (looks.lash_spacing, looks.lash_width)
        prog["iris_radius"] = float(self.face.fapu.IRISD0) / 2.0
        prog["light_direction"] = np.array([self.key_light, _unit(FILL_LIGHT[0])], np.float32).tobytes()
        prog["light_colour"] = np.array([KEY_LIGHT[1], FILL_LIGHT[1]], np.float32).tobytes()
        prog["ambient"] = AMBIENT
        camera = self.camera
        prog["world_to_clip"] = camera.matrix.T.astype(np.float32).tobytes()
        prog["camera_position"] = tuple(camera.position)
        prog["orthographic"] = camera.orthographic
        prog["view_direction"] = tuple(-camera.view[2, :3])
        prog["lighting"] = self.lighting
        prog["uv_space"] = prog["albedo"] = self._baking
        prog["uv_frame"] = (0.0, 0.0, 1.0, 1.0)
        prog["use_texture"] = self.texture is not None
        prog["skin_texture"] = 0
        prog["iris_texture"] = 1
        prog["brow_texture"] = 2

    def set_camera(self, camera: Camera) -> None:
        """Look from another camera (e.g. :func:`.camera.frame_points` with another view)."""
        self.camera = camera

    def set_texture(self, texture: np.ndarray | None) -> None:
        """Use an (H, W, 3) uint8 UV image as the skin's colour (row 0 = v 1, as images are stored)."""
        self.texture = None
        if texture is not None:
            img = np.asarray(texture)
            if img.ndim != 3 or img.shape[2] not in (3, 4) or img.dtype != np.uint8:
                raise RenderError(f"a skin texture is an (H, W, 3) uint8 image, got {img.shape} {img.dtype}",
                                  where="renderer", hint="convert it to 8-bit RGB first")
            img = np.ascontiguousarray(img[::-1, :, :3])
            tex = self.ctx.texture((img.shape[1], img.shape[0]), 3, img.tobytes(), alignment=1)
            tex.build_mipmaps()
            tex.repeat_x = tex.repeat_y = False
            self.texture = tex

    # -- drawing ---------------------------------------------------------------------------

    def _upload(self, pose: Pose) -> None:
        vertices = pose.vertices
        vertex_data(self.layout, vertices, out=self._vertex_data)
        self.dynamic.write(self._vertex_data)
        if self.patch is not None:
            self.patch_buffers[0].write(refined_vertices(self.patch, self._vertex_data, out=self._patch_data))
        if self.lashes is not None:
            self.lash_buffers[0].write(lash_vertices(self.lashes, vertices, out=self._lash_data))
        centres, axes, pupils = [], [], []
        for part, joint in _EYES:
            centre = vertices[self.face.mesh.joints[joint]]
            front = vertices[pose.parts[part].start]  # vertex 0 of an eyeball is its front pole
            centres.append(centre)
            axes.append(_unit(front - centre))
            pupils.append(max(pose.pupil_diameter.get(part, 0.0), 0.0) / 2.0)
        prog = self.uniforms
        prog["eye_centre"] = np.array(centres, np.float32).tobytes()
        prog["eye_axis"] = np.array(axes, np.float32).tobytes()
        prog["pupil_radius"] = np.array(pupils, np.float32).tobytes()
        prog["nose_wrinkle"] = nose_wrinkle(self._neutral_points,
                                                  points_of(self.face.mesh.fp_labels, pose.feature_points))

    def draw(self, pose: Pose) -> None:
        """Draw a pose into the framebuffer (resolved if anti-aliased); read it with :meth:`read`."""
        if pose.vertices.shape != self.face.mesh.vertices.shape:
            raise RenderError(f"pose has {len(pose.vertices)} vertices, the face {self.face.mesh.n_vertices}",
                              where="renderer", hint="render poses of the face the renderer was made for")
        ctx = self.ctx
        self._apply_uniforms()
        self._upload(pose)
        target = self.ms_fbo or self.fbo
        target.use()
        bg = self.materials.background
        target.clear(bg[0], bg[1], bg[2], 1.0, depth=1.0)
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        if self.texture is not None:
            self.texture.use(0)
        self.iris_texture.use(1)
        self.brow_texture.use(2)
        for first, count in self.face_ranges:
            if count:
                self.vao.render(vertices=count, first=first)
        if self.brow_range[1]:
            self.brow_vao.render(vertices=self.brow_range[1], first=self.brow_range[0])
        if self.patch_vao is not None:
            self.patch_vao.render()
        if self.eye_vao is not None:
            self.eye_vao.render(vertices=self.eye_range[1], first=self.eye_range[0])
        if self.lash_vao is not None and self.texture is None:  # a photo texture has its own lashes, as its brows
            self.lash_vao.render()
        if self.ms_fbo is not None:
            ctx.copy_framebuffer(self.fbo, self.ms_fbo)

    def albedo(self) -> Albedo:
        """The head's own colours in its UV image, as this renderer shows them under a unit light (the mouth's
        shadow in, the light's direction and shine out): the skin (lips, brows, the mouth's dark) and, where its UV
        map places them apart from the skin, the teeth (gums, gaps, the back teeth's shadow) and the tongue;
        :class:`Albedo`: the ``(height, width, 3)`` uint8 image, row 0 = v 1 (as :meth:`set_texture` takes one), the
        parts it holds, which part each texel belongs to, the left eyeball's own image (:data:`EYE_ALBEDO_SIZE`
        a side: sclera, the iris with its detail, the pupil at rest) and the teeth's (:data:`TEETH_ALBEDO_SIZE` a
        side over their islands' box, ``teeth_frame``: gaps, gums, the back teeth's shadow).

        Drawn by the face shader itself in texture space, so a viewer that has only textures (a glTF one, the
        browser pages) shows the brows, lips and mouth this renderer draws. Texels off every island take their
        nearest island texel's colour, so that mipmaps and bilinear lookups at an island's edge find no
        background."""
        ctx = self.ctx
        self._baking = True
        try:
            self._apply_uniforms()
            self._upload(self.face.neutral())
        finally:
            self._baking = False
        self.fbo.use()
        self.fbo.clear(0.0, 0.0, 0.0, 0.0)
        ctx.disable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)
        if self.texture is not None:
            self.texture.use(0)
        self.iris_texture.use(1)
        self.brow_texture.use(2)
        mesh, lay = self.face.mesh, self.layout
        counts = {part: len(mesh.triangles.get(part, ())) for part in PART_MATERIAL}  # build_layout's order
        starts = dict(zip(counts, np.r_[0, np.cumsum(list(counts.values()))[:-1]].astype(int)))
        # the skin's (the neck's cap has no UVs of its own), its triangles about the brows by the brow variant
        self.vao.render(vertices=self.brow_range[0], first=0)
        if self.brow_range[1]:
            self.brow_vao.render(vertices=self.brow_range[1], first=self.brow_range[0])
        baked = self._read_rgba()
        taken = baked[..., 3] > 0
        owner = np.where(taken, 0, 255).astype(np.uint8)
        if not taken.any():
            raise RenderError("the skin has no texture coordinates to bake into", where="renderer",
                              hint="give the head's skin a UV map")
        parts = ["skin"]
        for part in BAKED_WITH_SKIN:  # each where its UVs lie apart from what is baked (else it would paint over it)
            n = counts.get(part, 0)
            uv = lay.uv[lay.indices[starts[part]:starts[part] + n].ravel()]
            if not n or uv.min() < 0.0 or uv.max() > 1.0:  # none, or off the image (another UV tile)
                continue
            self.fbo.clear(0.0, 0.0, 0.0, 0.0)
            self.vao.render(vertices=3 * n, first=3 * starts[part])
            drawn = self._read_rgba()
            mine = drawn[..., 3] > 0
            # none (UVs collapsed to a point), or on another island (islands that touch share an edge's texels)
            if mine.sum() == 0 or (mine & taken).sum() > OVERLAP_SHARE * mine.sum():
                continue
            baked[mine], taken = drawn[mine], taken | mine
            owner[mine] = len(parts)
            parts.append(part)
        image = _filled(baked)
        eye = None
        if counts.get("eye_l"):
            eye = self._bake_alone((self.eye_vao or self.vao), starts["eye_l"], counts["eye_l"], EYE_ALBEDO_SIZE)
        teeth, frame = None, None
        # where the head's image could hold both teeth apart (islands of their own, no overlap): one block of the index
        # buffer, upper then lower (laid over each other, the upper wore the lower's colours)
        if all(part in parts for part in TEETH):
            uv = lay.uv[lay.indices[starts[TEETH[0]]:starts[TEETH[1]] + counts[TEETH[1]]].ravel()]
            lo, span = uv.min(axis=0), np.maximum(uv.max(axis=0) - uv.min(axis=0), 1e-6)
            frame = (float(lo[0]), float(lo[1]), float(span[0]), float(span[1]))
            teeth = self._bake_alone(self.vao, starts[TEETH[0]], counts[TEETH[0]] + counts[TEETH[1]],
                                     TEETH_ALBEDO_SIZE, frame)
        return Albedo(image, tuple(parts), eye, np.ascontiguousarray(owner[::-1]), teeth, frame)

    def _bake_alone(self, vao, first: int, count: int, size: int,
                    frame: tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0)) -> np.ndarray:
        """One part's triangles (``count`` from ``first``) baked alone into an image of its own, ``size`` texels a side
        (a framebuffer of its own: a renderer the size of a small photo bakes them as finely), over ``frame`` of the UV
        square: its colours at a density of their own."""
        colour = self.ctx.renderbuffer((size, size), 4)
        fbo = self.ctx.framebuffer(colour)
        try:
            fbo.use()
            fbo.clear(0.0, 0.0, 0.0, 0.0)
            self.uniforms["uv_frame"] = frame
            vao.render(vertices=3 * count, first=3 * first)
            rgba = np.empty((size, size, 4), np.uint8)
            fbo.read_into(rgba, components=4, alignment=1)
            return _filled(rgba)
        finally:
            self.uniforms["uv_frame"] = (0.0, 0.0, 1.0, 1.0)
            fbo.release()
            colour.release()
            self.fbo.use()

    def _read_rgba(self) -> np.ndarray:
        """The framebuffer as (H, W, 4) uint8, bottom row first (GL's order)."""
        rgba = np.empty((self.height, self.width, 4), np.uint8)
        self.fbo.read_into(rgba, components=4, alignment=1)
        return rgba

    def read(self, out: np.ndarray | None = None) -> np.ndarray:
        """The last drawn image as (H, W, 3) uint8, top row first (into ``out`` if given)."""
        self.fbo.read_into(self._pixels, components=3, alignment=1)
        if out is None:
            out = np.empty_like(self._pixels)
        np.copyto(out, self._pixels[::-1])
        return out

    def render(self, pose: Pose, out: np.ndarray | None = None) -> np.ndarray:
        """Draw and read back one pose."""
        self.draw(pose)
        return self.read(out)

    def release(self) -> None:
        """Free this renderer's GPU objects (the shared context stays)."""
        for obj in (self.vao, self.brow_vao, self.eye_vao, self.index, self.static, self.dynamic, self.fbo, self.ms_fbo,
                    self.texture, self.iris_texture, self.brow_texture, self.lash_vao, *(self.lash_buffers or ()),
                    self.patch_vao, *(self.patch_buffers or ())):
            if obj is not None:
                obj.release()

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc) -> None:
        self.release()
