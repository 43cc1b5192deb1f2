"""The skin's own colours baked into its UV image by the face shader (:meth:`mpeg4fa.render.Renderer.albedo`):
what a viewer that has only a texture (a glTF one, the browser pages) shows in place of the shader's procedural
brows, lips and mouth. Before it the exported and served heads had no brows at all (vertex colours cannot draw
them at the mesh's density), so the pages showed a browless face."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.export.gltf import RENDER_GAMMA
from mpeg4fa.render import Materials, Renderer, frame_points

pytestmark = pytest.mark.usefixtures("generic_head_installed")

BAKE = 1024
SIZE = 256
FACE_POINTS = ("4.1", "4.2", "4.5", "4.6", "8.3", "8.4", "2.1", "9.3")


@pytest.fixture(scope="module")
def baked(generic_face):
    with Renderer(generic_face, width=BAKE, height=BAKE, lighting=False, lashes=False) as r:
        return r.albedo()


@pytest.fixture(scope="module")
def albedo(baked) -> np.ndarray:
    return baked.image


def _renders(face, texture: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unlit front renders of the face drawn by the shader and of the face wearing ``texture`` as its skin."""
    camera = frame_points(np.array([face.mesh.fp(label) for label in FACE_POINTS]), SIZE, SIZE, view="front")
    with Renderer(face, width=SIZE, height=SIZE, camera=camera, lighting=False, lashes=False) as drawn, \
            Renderer(face, width=SIZE, height=SIZE, camera=camera, lighting=False, lashes=False,
                     texture=texture) as worn:
        return drawn.render(face.neutral()).astype(int), worn.render(face.neutral()).astype(int)


def test_the_baked_skin_shows_what_the_shader_draws(generic_face, albedo):
    """Worn as the skin's texture, the bake gives the face the shader draws: the brows and lips where they are
    (measured: mean difference 0.9 levels at 512 px from a 2048 bake, 0.09 % of pixels over 24, the brows' hair
    strokes blurred)."""
    assert albedo.shape == (BAKE, BAKE, 3) and albedo.dtype == np.uint8
    base = np.round(255.0 * (albedo / 255.0) ** RENDER_GAMMA).astype(np.uint8)  # shown colours -> the shader's base
    drawn, worn = _renders(generic_face, base)
    diff = np.abs(drawn - worn).max(axis=2)
    assert diff.mean() < 2.0 and (diff > 24).mean() < 0.01, (float(diff.mean()), float((diff > 24).mean()))
    brow = np.asarray(Materials().brows) * 255
    skin = np.asarray(Materials().skin.colour) * 255
    browish = lambda image: (np.abs(image - brow).sum(axis=2) < np.abs(image - skin).sum(axis=2) / 2)  # noqa: E731
    assert browish(drawn).sum() >= 150, int(browish(drawn).sum())  # the shader draws brows here
    assert (browish(worn) & browish(drawn)).sum() >= 0.8 * browish(drawn).sum()  # and the bake carries them


def test_texels_off_the_skin_take_their_nearest_skin_colour(albedo):
    """No texel keeps the clear colour (black): those off every island wear their nearest skin texel's colour, so
    that mipmaps and bilinear lookups at an island's edge find none; the UV square's top-left corner, far from the
    mouth's island, wears the skin's."""
    assert not (albedo.astype(int).sum(axis=2) == 0).any()
    shown = np.round(255.0 * np.asarray(Materials().skin.colour) ** (1.0 / RENDER_GAMMA))
    assert np.abs(albedo[0, 0].astype(float) - shown).max() <= 2, albedo[0, 0]


def _at_vertices(face, image: np.ndarray, part: str) -> tuple[np.ndarray, np.ndarray]:
    """Colours (RGB, float) of ``image`` at the UVs of ``part``'s GL vertices, and their detail coordinates
    (render/details.py)."""
    from mpeg4fa.render.scene import build_layout

    lay = build_layout(face.mesh)
    a, b = face.mesh.part_ranges[part]
    mine = (lay.source >= a) & (lay.source < b)
    uv = lay.uv[mine].astype(float)
    rows = np.clip(((1.0 - uv[:, 1]) * len(image)).astype(int), 0, len(image) - 1)
    cols = np.clip((uv[:, 0] * image.shape[1]).astype(int), 0, image.shape[1] - 1)
    return image[rows, cols].astype(float), lay.detail[mine]


def _luma(rgb: np.ndarray) -> np.ndarray:
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def test_the_teeth_and_tongue_are_baked_with_the_mouth_s_shadow(generic_face, baked):
    """The generic head's map keeps the teeth and tongue apart from the skin, so they are baked too: in a glTF
    viewer the premolars and molars showed as white fangs at the corners of an open mouth (the Python renderer
    shades them by their place along the arch). Measured at the vertices' texels: back teeth (4 and more along the
    arch) luma 29 / 38 (upper / lower) against the front teeth's brightest 233, the tongue's back 32 against its
    tip's 98."""
    assert baked.parts == ("skin", "teeth_upper", "teeth_lower", "tongue")
    for part in ("teeth_upper", "teeth_lower"):
        rgb, detail = _at_vertices(generic_face, baked.image, part)
        luma = _luma(rgb)
        front, back = luma[np.abs(detail[:, 0]) < 1.5], luma[np.abs(detail[:, 0]) >= 4.0]
        assert len(front) and len(back) and back.mean() < 0.2 * front.max(), (part, back.mean(), front.max())
    rgb, detail = _at_vertices(generic_face, baked.image, "tongue")
    luma = _luma(rgb)
    tip, rear = luma[detail[:, 1] < 8.0], luma[detail[:, 1] > 45.0]
    assert len(tip) and len(rear) and rear.mean() < 0.6 * tip.mean(), (rear.mean(), tip.mean())


def test_the_eyeball_is_baked_with_its_iris(generic_face, baked):
    """The eyeball's own image: pupil, iris (brown, with its detail) and sclera where the shader draws them, by the
    distance of each of the left eyeball's vertices from its axis (measured: the iris's middle ring luma 70 against
    the sclera's 189, RGB 96 / 66 / 37). Before it a viewer showed the iris only as far as the eyeball's vertex
    colours could (a flat disc)."""
    from mpeg4fa.render.renderer import EYE_ALBEDO_SIZE

    face = generic_face
    assert baked.eye is not None and baked.eye.shape == (EYE_ALBEDO_SIZE, EYE_ALBEDO_SIZE, 3)
    rgb, _ = _at_vertices(face, baked.eye, "eye_l")
    luma = _luma(rgb)
    from mpeg4fa.render.scene import build_layout

    lay, mesh = build_layout(face.mesh), face.mesh
    a, b = mesh.part_ranges["eye_l"]
    source = lay.source[(lay.source >= a) & (lay.source < b)]
    centre = mesh.vertices[mesh.joints["l-eye"]]
    axis = mesh.vertices[a] - centre  # vertex 0 of an eyeball is its front pole
    axis /= np.linalg.norm(axis)
    offset = mesh.vertices[source] - centre
    across = np.linalg.norm(offset - np.outer(offset @ axis, axis), axis=1)
    front = offset @ axis > 0
    iris = float(face.fapu.IRISD0) / 2.0
    ring = front & (across > 0.45 * iris) & (across < 0.85 * iris)
    sclera = front & (across > 1.3 * iris)
    assert ring.sum() >= 6 and sclera.sum() >= 6, (int(ring.sum()), int(sclera.sum()))
    assert luma[ring].mean() < 0.6 * luma[sclera].mean(), (luma[ring].mean(), luma[sclera].mean())
    red, blue = rgb[ring, 0].mean(), rgb[ring, 2].mean()
    assert red > 1.5 * blue, (red, blue)  # brown: the iris's colour through its pattern, not grey


def test_parts_off_the_image_or_on_baked_texels_are_not_baked(generic_face):
    """A part's UVs off the unit square (another UV tile) or over an island already baked leave it out of the bake
    (it would wear the image's edge, skin-coloured teeth, or another part's colours); found by review."""
    from dataclasses import replace

    from mpeg4fa.face import FaceModel

    mesh = generic_face.mesh
    uvs = dict(mesh.corner_uvs)
    uvs["tongue"] = uvs["tongue"] + (1.0, 0.0)  # another UV tile
    uvs["teeth_lower"] = uvs["teeth_upper"][:len(uvs["teeth_lower"])]  # onto the upper teeth's island
    face = FaceModel(replace(mesh, corner_uvs=uvs))
    with Renderer(face, width=256, height=256, lighting=False, lashes=False) as r:
        assert r.albedo().parts == ("skin", "teeth_upper")


def test_a_textured_renderer_bakes_its_own_texture(generic_face):
    """The bake binds the renderer's own skin texture (another renderer's drawn before it was still bound to the
    unit: found by review)."""
    red, green = (np.zeros((64, 64, 3), np.uint8) for _ in range(2))
    red[..., 0] = 255
    green[..., 1] = 255
    with Renderer(generic_face, width=128, height=128, texture=red) as first, \
            Renderer(generic_face, width=256, height=256, lighting=False, lashes=False, texture=green) as second:
        first.render(generic_face.neutral())
        image = second.albedo().image.astype(int)
    assert (image[..., 1] > image[..., 0]).mean() > 0.5
