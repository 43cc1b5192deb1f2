"""A decoded stream as a glTF binary (GLB): the head with its parts and looks, the FAPs baked as an animation.

Why glTF: it is what web viewers, game engines and DCC tools load, and its morph
targets with an animated ``weights`` channel play a talking face without any MPEG-4
decoder. Two ways to bake the stream:

* ``animation="morph"``: the head's 52 ARKit face units are the morph targets (named in
  ``mesh.extras.targetNames``, which three.js reads), and one LINEAR ``weights`` channel
  keyed at the frames' presentation times carries the weights the ARKit deformer gives
  them (:mod:`.arkit_units`; the lower teeth and tongue ride on the jaw and tongue units,
  the blink units are the deformer's lid turns). The face moves as the ARKit deformer's
  sculpted units move it: not the feature-point deformer's pose, and without its
  feature-point correction of the skin. The turns are node animation
  (:mod:`.gltf_motion`): the head turns (FAPs 48-50) about feature point 7.1, rigidly with
  its neck (the deformer fades the turn down the neck), and each eyeball, a mesh of its
  own, about its joint. Needs a head with face units (the generic head).
* ``animation="vertex"``: the face's own deformer poses every frame; each distinct pose is
  one morph target (all parts), and the weights channel selects pose k at frame k
  (LINEAR, so between two frames the vertices move straight from one pose to the next).
  Exact for any head and deformer; the file grows with the number of distinct poses.

Geometry is in metres (the model's millimetres / 1000), y up, the face looking along +z,
one primitive per drawn part (skin, eyes, teeth, tongue; in morph animation the eyes in
meshes of their own) with its material: base colours
of :mod:`mpeg4fa.render.materials`; the head's own colours (skin, lips, brows with their hairs, the dark of the
mouth; the tongue in the mouth's shadow; the teeth with gums and the back teeth's shadow in an image of their own,
about 9 texels a mm; the eyeball's sclera, iris and pupil in an image of its own) baked by the
renderer's face shader into the head's UV image (:meth:`.Renderer.albedo`, embedded as PNG), so that any viewer
shows the brows, lips and mouth our renderer draws (where no GL context can be made, the lips and the mouth's dark
go into the skin's vertex colours, iris and pupil into the eyes', and the rest is left out); or a skin texture (e.g.
an FDP's) embedded as PNG with the baked teeth and tongue laid on their islands, the mouth's dark in the vertex
colours. The lashes are cards of their own (:mod:`mpeg4fa.render.lashes`), grown from the lids at rest and in each
target's pose, their strands an alpha-masked texture (none with a photo texture, which has the person's own).
glTF carries no sound: the stream's
WAV is written beside the GLB under its name (``head.glb`` -> ``head.wav``).
"""
from __future__ import annotations

import io
import os
import shutil
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pygltflib as gl

from mpeg4fa import __version__
from mpeg4fa.atomic import atomic_outputs
from mpeg4fa.decoded import resolve
from mpeg4fa.errors import MpegFaError
from mpeg4fa.export.arkit_units import arkit_units
from mpeg4fa.export.glb_buffer import GlbBuffer
from mpeg4fa.export.gltf_motion import EYES, HEAD_CENTRE, eye_turns, head_turns
from mpeg4fa.face.model import FaceModel
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.render.materials import TEETH, Material, Materials
from mpeg4fa.render.scene import SceneLayout, build_layout, vertex_normals
from mpeg4fa.render.timing import presentation_times

ANIMATIONS = ("morph", "vertex")
RENDER_GAMMA = 1.15
"""The face shader's output curve (``pow(rgb, 1 / 1.15)`` in ``render/shaders/face.frag.glsl``)."""
MM = 0.001  # model millimetres -> glTF metres
ALBEDO_SIZE = 2048
"""Texels a side of the baked skin image: the generic head's face spans a sixth of its UV square (about 2 texels
a mm here, a texel a pixel where the browser pages show the head; 59 KiB of PNG, baked in about a second)."""
PART_LOOK = {"skin": "skin", "eye_l": "sclera", "eye_r": "sclera", "teeth_upper": "teeth", "teeth_lower": "teeth",
             "tongue": "tongue", "lashes": "lashes"}
"""Drawn part -> the :class:`~mpeg4fa.render.materials.Materials` entry it wears, in the renderer's order."""
LASH_CUTOFF = 0.35
"""Alpha below which a viewer leaves a lash texel out (glTF ``MASK``): under a half, so that strands thinner
than a texel at a distance (their mip levels' coverage) still show as a lash line."""
Progress = Callable[[int, int], None]


class ExportError(MpegFaError):
    """A stream or head that cannot be written as asked."""


@dataclass(frozen=True)
class GlbExport:
    path: Path
    n_parts: int
    n_targets: int
    n_frames: int         # animation key frames (stream frames with distinct presentation times)
    duration: float       # seconds, first to last key
    animation: str
    audio: Path | None    # the WAV beside the GLB, if any
    bytes: int
    skin: str = "albedo"  # what the skin's texture holds: albedo (its own colours), photo, or colours (no texture)


@dataclass(frozen=True)
class _Part:
    name: str
    source: np.ndarray   # (n,) mesh vertex of each glTF vertex
    uv: np.ndarray       # (n, 2) glTF texture coordinates (v down)
    colour: np.ndarray   # (n, 3) linear vertex colour
    indices: np.ndarray  # (t, 3) local vertex indices


@dataclass(frozen=True)
class _Lashes:
    """The lash cards (:mod:`mpeg4fa.render.lashes`) as a part of their own: their vertices are grown from the
    posed lids, not mesh vertices, so they carry their rest, normals and each morph target's offsets."""

    part: _Part           # source: 0 .. 3K - 1 into the arrays below
    rest: np.ndarray      # (3K, 3) mm
    normals: np.ndarray   # (3K, 3)
    shapes: np.ndarray    # (T, 3K, 3) mm, grown from rest + each of the mesh's targets


def export_glb(stream: FapStream, face: FaceModel, path: str | os.PathLike, *, animation: str = "morph",
               audio: str | os.PathLike | None = None, texture: np.ndarray | None = None,
               materials: Materials | None = None, progress: Progress | None = None) -> GlbExport:
    """Write ``stream`` played on ``face`` as a GLB at ``path`` (and ``audio`` copied beside it as a WAV)."""
    if animation not in ANIMATIONS:
        raise ExportError(f"unknown animation {animation!r}", hint=f"one of {', '.join(ANIMATIONS)}")
    target, audio_path = Path(path), Path(audio) if audio is not None else None
    if audio_path is not None:
        _check_wav(audio_path)
    wav_out = target.with_suffix(".wav") if audio_path is not None else None
    if wav_out is not None and _same_file(wav_out, audio_path):
        wav_out = None  # the speech is already beside the GLB under its name
    data, summary = build_glb(stream, face, animation=animation, texture=texture, materials=materials,
                              progress=progress, name=target.stem)
    with atomic_outputs(target, wav_out) as (glb_tmp, wav_tmp):
        glb_tmp.write_bytes(data)
        if wav_tmp is not None:
            shutil.copyfile(audio_path, wav_tmp)
    return GlbExport(path=target, audio=(target.with_suffix(".wav") if audio_path is not None else None),
                     bytes=len(data), animation=animation, **summary)


def build_glb(stream: FapStream, face: FaceModel, *, animation: str = "morph", texture: np.ndarray | None = None,
              materials: Materials | None = None, progress: Progress | None = None,
              name: str = "mpeg4fa") -> tuple[bytes, dict]:
    """The GLB bytes and ``n_parts``/``n_targets``/``n_frames``/``duration`` (see :func:`export_glb`)."""
    values, times = _keyed_frames(stream)
    looks = materials or Materials()
    layout = build_layout(face.mesh)
    textured: tuple[str, ...] = ("skin",)  # the parts that wear the texture
    if texture is not None:
        texture = _checked(texture)
        skin, baked = "photo", _albedo(face, looks, (texture.shape[1], texture.shape[0]))
        if baked is not None:  # the photo's skin, the teeth's and tongue's own colours on their islands
            texture, textured = _with_parts(texture, baked)
    else:
        baked = _albedo(face, looks)
        skin = "albedo" if baked is not None else "colours"
        texture, textured = (baked.image, _wearing(baked.parts)) if baked is not None else (None, ())
    eye_image = baked.eye if baked is not None else None
    teeth_image, teeth_frame = (baked.teeth, baked.teeth_frame) if baked is not None else (None, None)
    parts = _parts(face, layout, looks, skin, eye_image is not None, teeth_frame)
    rest = face.mesh.vertices
    if animation == "morph":
        units = arkit_units(face, where=name)
        shapes, names, weights = units.shapes, list(units.names), units.weights(values)
        if progress:
            progress(len(values), len(values))
    else:
        shapes, names, weights = _frame_poses(face, values, rest, progress)

    gltf = gl.GLTF2(asset=gl.Asset(version="2.0", generator=f"mpeg4fa {__version__}"), scene=0)
    buf = GlbBuffer(gltf)
    worn = dict.fromkeys(textured, _add_texture(gltf, buf, texture, "head") if texture is not None else None)
    if eye_image is not None:  # both eyeballs' maps are the left one's
        worn.update(dict.fromkeys(EYES, _add_texture(gltf, buf, eye_image, "eye", mipmaps=False)))
    if teeth_image is not None:  # the teeth's own image, some 9 texels a mm (in the head's image about 1)
        worn.update(dict.fromkeys(TEETH, _add_texture(gltf, buf, teeth_image, "teeth")))
    normals = vertex_normals(rest, layout.triangles, layout.incidence)

    lashes = _lashes(face, shapes) if skin != "photo" else None  # a photo has the person's own lashes
    if lashes is not None:
        parts.append(lashes.part)
        worn["lashes"] = _add_texture(gltf, buf, _lash_texture(looks), "lashes", repeat=True)

    def arrays(part: _Part, targets: np.ndarray | None) -> tuple:
        """Rest, normals and targets a part's ``source`` indexes: the mesh's, or the lash cards' own."""
        if part.name != "lashes":
            return rest, normals, targets
        return lashes.rest, lashes.normals, lashes.shapes if targets is not None else None

    def mesh(mesh_name: str, members: list[_Part], targets: np.ndarray | None) -> int:
        prims = [_primitive(gltf, buf, part, *arrays(part, targets), looks, worn.get(part.name)) for part in members]
        extra = ({"weights": [0.0] * len(names), "extras": {"targetNames": names}} if targets is not None
                 else {"weights": None})
        gltf.meshes.append(gl.Mesh(name=mesh_name, primitives=prims, **extra))
        return len(gltf.meshes) - 1

    if animation == "vertex":  # one mesh, every part baked
        gltf.nodes.append(gl.Node(name=name, mesh=mesh(name, parts, shapes)))
        channels = [(0, gl.WEIGHTS, weights)]
    else:
        channels = _rigid_scene(gltf, face, values, parts, name, lambda n, members, morph: mesh(
            n, members, shapes if morph else None))
        channels.insert(0, (1, gl.WEIGHTS, weights))
    gltf.scenes.append(gl.Scene(name=name, nodes=[0]))
    _add_animation(gltf, buf, name, times, channels)
    gltf.buffers.append(gl.Buffer(byteLength=0))
    blob = buf.blob()
    gltf.buffers[0].byteLength = len(blob)
    gltf.set_binary_blob(blob)
    out = b"".join(gltf.save_to_bytes())
    duration = float(times[-1] - times[0]) if len(times) else 0.0
    return out, {"n_parts": len(parts), "n_targets": len(names), "n_frames": len(times), "duration": duration,
                 "skin": skin}


def _lashes(face: FaceModel, shapes: np.ndarray) -> _Lashes | None:
    """The lash cards at rest and grown from rest + each target's offsets (None where the face has no lid margins)."""
    from mpeg4fa.render.lashes import build_lashes, lash_vertices, strand_uv

    layout = build_lashes(face.mesh)
    if layout is None:
        return None
    rest = face.mesh.vertices
    at_rest = lash_vertices(layout, rest).astype(np.float64)
    grown = np.empty((len(shapes), len(at_rest), 3), np.float32)
    for k, shape in enumerate(shapes):
        grown[k] = lash_vertices(layout, rest + shape)[:, :3] - at_rest[:, :3]
    n = len(at_rest)
    part = _Part("lashes", np.arange(n), strand_uv(layout), np.ones((n, 3)), layout.indices.astype(np.int64))
    return _Lashes(part, at_rest[:, :3], at_rest[:, 3:], grown)


def _lash_texture(looks: Materials) -> np.ndarray:
    """The strands (:func:`~mpeg4fa.render.lashes.strand_image`) as RGBA: the lashes' colour as our renderer
    shows it (sRGB bytes), their coverage as alpha."""
    from mpeg4fa.render.lashes import strand_image

    alpha = strand_image()
    colour = np.rint(255 * np.asarray(looks.lashes, np.float64) ** (1.0 / RENDER_GAMMA)).astype(np.uint8)
    return np.dstack([np.broadcast_to(colour, alpha.shape + (3,)), alpha])


def part_sources(face: FaceModel) -> dict[str, np.ndarray]:
    """Per drawn part (a primitive of :func:`build_glb`, named in its ``extras.part``): the mesh vertex of each of
    its GL vertices, so that a page moving the mesh itself (the FBA player) writes each where it belongs."""
    return {part.name: part.source for part in _parts(face, build_layout(face.mesh), Materials(), "colours")}


def _keyed_frames(stream: FapStream) -> tuple[np.ndarray, np.ndarray]:
    """Resolved values and presentation times, one per distinct time (the last frame shown at a time wins)."""
    if not len(stream):
        raise ExportError("the stream has no frames", hint="export a stream with at least one frame")
    values, times = resolve(stream), presentation_times(stream)
    keep = np.r_[np.diff(times) > 1e-9, True]
    return values[keep], times[keep]


def _frame_poses(face: FaceModel, values: np.ndarray, rest: np.ndarray,
                 progress: Progress | None) -> tuple[np.ndarray, list[str], np.ndarray]:
    """One target per distinct frame of values (its vertex deltas), and weights selecting it at its frames."""
    distinct, first, which = np.unique(values, axis=0, return_index=True, return_inverse=True)
    which = which.reshape(-1)
    shapes = np.empty((len(distinct), len(rest), 3), np.float32)
    for k, row in enumerate(distinct):
        shapes[k] = face.pose_values(row).vertices - rest
        if progress:
            progress(k + 1, len(distinct))
    weights = np.zeros((len(values), len(distinct)))
    weights[np.arange(len(values)), which] = 1.0
    return shapes, [f"frame {int(f)}" for f in first], weights


def _albedo(face: FaceModel, looks: Materials, size: tuple[int, int] = (ALBEDO_SIZE, ALBEDO_SIZE)):
    """The head's own colours in its UV image (:meth:`.Renderer.albedo`, ``size`` texels), or None where they cannot
    be baked."""
    import moderngl

    from mpeg4fa.render import Renderer
    from mpeg4fa.render.errors import RenderError

    try:
        with Renderer(face, width=size[0], height=size[1], materials=looks, lighting=False, lashes=False) as r:
            return r.albedo()
    except (RenderError, moderngl.Error):  # no GL context, no UV map, or a framebuffer this GL cannot make
        return None


def _with_parts(photo: np.ndarray, baked) -> tuple[np.ndarray, tuple[str, ...]]:
    """A photo texture with the baked parts other than the skin (teeth, tongue) laid on their own islands, and the
    parts that wear it (the photo's texels elsewhere as they were)."""
    wearing = _wearing(baked.parts)
    out = np.array(photo[:, :, :3])
    for k, part in enumerate(baked.parts):
        if part != "skin" and part in wearing:
            here = baked.owner == k
            out[here] = baked.image[here]
    return out, wearing


def _wearing(baked: tuple[str, ...]) -> tuple[str, ...]:
    """The parts that wear the baked image: those it holds, but the teeth both or neither (one material)."""
    return tuple(p for p in baked if p not in TEETH or all(t in baked for t in TEETH))


def _parts(face: FaceModel, layout: SceneLayout, looks: Materials, skin: str, eyes_baked: bool = False,
           teeth_frame: tuple[float, float, float, float] | None = None) -> list[_Part]:
    """The renderer's GL vertices (one per mesh vertex and UV) split into one set per drawn part; the teeth's UVs over
    ``teeth_frame`` of the UV square where they wear their own image (:attr:`.Albedo.teeth`)."""
    mesh = face.mesh
    parts, tri_start = [], 0
    for part in PART_LOOK:
        tris = mesh.triangles.get(part)
        if tris is None or not len(tris):
            continue
        a, b = mesh.part_ranges[part]
        mine = np.flatnonzero((layout.source >= a) & (layout.source < b))
        indices = layout.indices[tri_start:tri_start + len(tris)].astype(np.int64) - mine[0]
        tri_start += len(tris)
        uv = layout.uv[mine].astype(np.float64)
        if teeth_frame is not None and part in TEETH:
            uv = (uv - teeth_frame[:2]) / teeth_frame[2:]
        colour = _colours(face, part, layout, mine, looks, skin, eyes_baked)
        parts.append(_Part(part, layout.source[mine], np.c_[uv[:, 0], 1.0 - uv[:, 1]], colour, indices))
    return parts


def _colours(face: FaceModel, part: str, layout: SceneLayout, mine: np.ndarray, looks: Materials,
             skin: str, eyes_baked: bool = False) -> np.ndarray:
    """Per-vertex linear colours, multiplied by the material's base colour (white where they are set here).
    ``skin``: what the skin's texture holds: ``albedo`` all of its colours, ``photo`` a photo's (the mouth's dark
    goes on it here), ``colours`` none (no texture: skin, lips and the mouth's dark here); ``eyes_baked``: the
    eyeballs wear their own baked image (else iris and pupil go here)."""
    n = len(mine)
    textured = skin != "colours"
    if part == "skin" and skin == "albedo":
        return np.ones((n, 3))
    if part == "skin":
        base = np.ones((n, 3)) if textured else np.tile(shown_colour(looks.skin.colour), (n, 1))
        if not textured:
            base += layout.lips[mine, None] * (shown_colour(looks.lips) - base)
        cavity = shown_colour(looks.cavity) / (1.0 if not textured else shown_colour(looks.skin.colour))
        return base + layout.cavity[mine, None] * (np.minimum(cavity, 1.0) - base)
    if part in EYES:
        return np.ones((n, 3)) if eyes_baked else _eye_colours(face, part, layout.source[mine], looks)
    return np.ones((n, 3))


def shown_colour(colour) -> np.ndarray:
    """A :mod:`~mpeg4fa.render.materials` colour as the glTF linear colour that a viewer shows as our renderer
    does: the face shader writes ``rgb ** (1 / RENDER_GAMMA)`` straight to 8-bit pixels, a glTF viewer
    sRGB-encodes its linear result, so the colour shown is decoded from sRGB."""
    shown = np.asarray(colour, np.float64) ** (1.0 / RENDER_GAMMA)
    return np.where(shown <= 0.04045, shown / 12.92, ((shown + 0.055) / 1.055) ** 2.4)


def _eye_colours(face: FaceModel, part: str, source: np.ndarray, looks: Materials) -> np.ndarray:
    """Sclera, iris and pupil by distance from the eye's axis (through its pupil point), as the shader draws them."""
    mesh = face.mesh
    a, b = mesh.part_ranges[part]
    centre = mesh.vertices[a:b].mean(axis=0)
    pupil = mesh.fp("3.5" if part == "eye_l" else "3.6")
    axis = (pupil - centre) / np.linalg.norm(pupil - centre)
    offset = mesh.vertices[source] - centre
    along = offset @ axis
    across = np.linalg.norm(offset - along[:, None] * axis, axis=1)
    iris_r = float(face.fapu.IRISD0) / 2.0
    pupil_r = float(face.neutral().pupil_diameter[part]) / 2.0
    colour = np.ones((len(source), 3))
    front = along > 0
    sclera = shown_colour(looks.sclera.colour)
    colour[front & (across <= iris_r)] = shown_colour(looks.iris) / sclera
    colour[front & (across <= pupil_r)] = shown_colour(looks.pupil) / sclera
    return np.minimum(colour, 1.0)


def _material(gltf: gl.GLTF2, name: str, look: Material, texture: int | None, vertex_coloured: bool) -> int:
    colour = ([1.0, 1.0, 1.0] if texture is not None or (vertex_coloured and name == "skin")
              else shown_colour(look.colour).tolist())
    pbr = gl.PbrMetallicRoughness(baseColorFactor=[*map(float, colour), 1.0], metallicFactor=0.0,
                                  roughnessFactor=float(np.sqrt(2.0 / (look.shininess + 2.0))),
                                  baseColorTexture=gl.TextureInfo(index=texture) if texture is not None else None)
    cards = name == "lashes"  # strands cut out of cards seen from both sides
    gltf.materials.append(gl.Material(name=name, pbrMetallicRoughness=pbr, doubleSided=name == "skin" or cards,
                                      alphaMode=gl.MASK if cards else gl.OPAQUE,
                                      alphaCutoff=LASH_CUTOFF if cards else None))
    return len(gltf.materials) - 1


def _primitive(gltf: gl.GLTF2, buf: GlbBuffer, part: _Part, rest: np.ndarray, normals: np.ndarray,
               shapes: np.ndarray | None, looks: Materials, texture: int | None) -> gl.Primitive:
    look_name = PART_LOOK[part.name]
    names = [m.name for m in gltf.materials]
    look = getattr(looks, look_name)
    material = names.index(look_name) if look_name in names else _material(
        gltf, look_name, look if isinstance(look, Material) else Material(look, 0.0, 4.0), texture, True)
    attributes = gl.Attributes(
        POSITION=buf.accessor((rest[part.source] * MM).astype(np.float32), target=gl.ARRAY_BUFFER, bounds=True),
        NORMAL=buf.accessor(normals[part.source].astype(np.float32), target=gl.ARRAY_BUFFER),
        COLOR_0=buf.accessor(part.colour.astype(np.float32), target=gl.ARRAY_BUFFER))
    if texture is not None:
        attributes.TEXCOORD_0 = buf.accessor(part.uv.astype(np.float32), target=gl.ARRAY_BUFFER)
    index_type = np.uint16 if len(part.source) <= 0xFFFF else np.uint32
    indices = buf.accessor(part.indices.reshape(-1).astype(index_type), target=gl.ELEMENT_ARRAY_BUFFER)
    targets = None if shapes is None else [gl.Attributes(POSITION=buf.morph_target(shape[part.source] * MM))
                                           for shape in shapes]
    return gl.Primitive(attributes=attributes, indices=indices, material=material, mode=gl.TRIANGLES,
                        targets=targets, extras={"part": part.name})


def _add_texture(gltf: gl.GLTF2, buf: GlbBuffer, texture: np.ndarray, name: str = "skin", mipmaps: bool = True,
                 repeat: bool = False) -> int:
    """``texture`` embedded as PNG; ``mipmaps`` off for a map whose triangles stretch across it (the eyeball's
    front-pole fan and its seam: a viewer's mip level there is its coarsest, a light streak across the iris);
    ``repeat``: across u, and its alpha kept (the lashes' strands; other textures are opaque RGB)."""
    from PIL import Image

    img = _checked(texture)
    png = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(img if repeat else img[:, :, :3])).save(png, format="PNG")
    gltf.samplers.append(gl.Sampler(magFilter=gl.LINEAR, minFilter=gl.LINEAR_MIPMAP_LINEAR if mipmaps else gl.LINEAR,
                                    wrapS=gl.REPEAT if repeat else gl.CLAMP_TO_EDGE, wrapT=gl.CLAMP_TO_EDGE))
    gltf.images.append(gl.Image(bufferView=buf.view(png.getvalue()), mimeType="image/png", name=name))
    gltf.textures.append(gl.Texture(sampler=len(gltf.samplers) - 1, source=len(gltf.images) - 1))
    return len(gltf.textures) - 1


def _checked(texture: np.ndarray) -> np.ndarray:
    img = np.asarray(texture)
    if img.ndim != 3 or img.shape[2] not in (3, 4) or img.dtype != np.uint8 or min(img.shape[:2]) < 1:
        raise ExportError(f"a skin texture is an (H, W, 3) uint8 image, got {img.shape} {img.dtype}",
                          hint="convert it to 8-bit RGB first")
    return img


def _rigid_scene(gltf: gl.GLTF2, face: FaceModel, values: np.ndarray, parts: list[_Part], name: str,
                 mesh) -> list[tuple[int, str, np.ndarray]]:
    """Nodes for morph animation: a head node turning about 7.1 (node 0), the face mesh under it (node 1: the
    morph targets), and each eyeball as its own mesh under a pivot node at its joint; the channels
    (node, path, values per key frame) of the turns that happen."""
    head = head_turns(face, values)
    centre = face.mesh.fp(HEAD_CENTRE) if head is not None else np.zeros(3)
    gltf.nodes.append(gl.Node(name=f"{name} head", translation=_metres(centre) if head is not None else None))
    channels = [] if head is None else [(0, gl.ROTATION, head.rotations)]
    face_parts = [p for p in parts if p.name not in EYES]
    gltf.nodes.append(gl.Node(name=name, mesh=mesh(name, face_parts, True),
                              translation=_metres(-centre) if head is not None else None))
    children = [1]
    for part in (p for p in parts if p.name in EYES):
        eye = eye_turns(face, values, part.name)
        pivot = len(gltf.nodes)
        at = _metres(eye.centre - centre)
        gltf.nodes.append(gl.Node(name=f"{name} {part.name}", translation=at, children=[pivot + 1]))
        gltf.nodes.append(gl.Node(name=part.name, mesh=mesh(part.name, [part], False),
                                  translation=_metres(-eye.centre)))
        children.append(pivot)
        if eye.rotations is not None:
            channels.append((pivot, gl.ROTATION, eye.rotations))
        if eye.offsets is not None:
            channels.append((pivot, gl.TRANSLATION, np.asarray(at) + eye.offsets * MM))
    gltf.nodes[0].children = children
    return channels


def _metres(point_mm: np.ndarray) -> list[float]:
    return [float(c) * MM for c in point_mm]


def _add_animation(gltf: gl.GLTF2, buf: GlbBuffer, name: str, times: np.ndarray,
                   channels: list[tuple[int, str, np.ndarray]]) -> None:
    """One animation, every channel keyed at the frames' presentation times, LINEAR (rotations: spherical)."""
    t = buf.accessor(times.astype(np.float32), bounds=True)
    samplers, targets = [], []
    for node, path, keyed in channels:
        output = np.ascontiguousarray(keyed, np.float32)
        samplers.append(gl.AnimationSampler(input=t, output=buf.accessor(output.reshape(-1) if path == gl.WEIGHTS
                                                                          else output),
                                            interpolation=gl.ANIM_LINEAR))
        targets.append(gl.AnimationChannel(sampler=len(samplers) - 1,
                                           target=gl.AnimationChannelTarget(node=node, path=path)))
    gltf.animations.append(gl.Animation(name=name, samplers=samplers, channels=targets))


def _check_wav(path: Path) -> None:
    """Only a RIFF/WAVE file is copied beside the GLB (the name says .wav)."""
    with open(path, "rb") as f:
        head = f.read(12)
    if len(head) < 12 or head[:4] != b"RIFF" or head[8:12] != b"WAVE":
        raise ExportError("not a WAV file (no RIFF/WAVE header)", where=str(path),
                          hint="convert the speech to WAV first, e.g. `ffmpeg -i IN -ac 1 OUT.wav`")


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and os.path.samefile(a, b)
    except OSError:
        return False
