"""The sender's texture (FDP case 3): an FDP built from two photos, as ``encode --fdp-out`` does, plays textured.

The photos are unlit orthographic renders of a head painted with a colour field
over 3D space, their feature points that head's own, projected with the same
camera; the FDP carries the front photo and the points' texture coordinates into
it. A head calibrated to that FDP (the same head or the other one) must show, at
each feature point, the photo's colour at the point's texture coordinate.
"""
from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.fba.stream import FapStream
from mpeg4fa.fdp import Fdp, TextureImage, fdp_from_photos
from mpeg4fa.render import RenderError, play, snapshot
from mpeg4fa.render.camera import frame_points
from mpeg4fa.render.fdp_texture import bake_fdp_texture, fdp_skin_texture
from mpeg4fa.render.renderer import Renderer
from mpeg4fa.render.scene import vertex_normals
from mpeg4fa.render.texture import PhotoView, bake_texture, uv_rasterise

PHOTO = 384     # the sender's photos
VIEW = 512      # the receiver's renders
SIZE = 512      # texture size of the direct bakes


def field(p: np.ndarray) -> np.ndarray:
    """Smooth colours (0-255) of 3D points, different on the face's two sides: wavelengths of 7-12 cm."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    r = 128 + 90 * np.sin(2 * np.pi * y / 85) * np.cos(2 * np.pi * x / 105) + 30 * np.sin(2 * np.pi * x / 100)
    g = 128 + 100 * np.cos(2 * np.pi * z / 75 + 0.5)
    b = 128 + 100 * np.sin(2 * np.pi * (y + z) / 115 + x * x / 3000)
    return np.clip(np.stack([r, g, b], -1), 0, 255)


class Sender:
    """A head photographed from the front and the left, and the FDP built from the two photos."""

    def __init__(self, face) -> None:
        self.face = face
        raster = uv_rasterise(face.mesh, SIZE)
        self.truth = np.rint(field(raster.position.astype(float))).astype(np.uint8)
        self.photos, self.points = {}, {}
        mesh = face.mesh
        for view in ("front", "left"):
            cam = frame_points(mesh.feature_points(), PHOTO, PHOTO, view=view, orthographic=True)
            with Renderer(face, width=PHOTO, height=PHOTO, camera=cam, texture=self.truth, lighting=False) as r:
                self.photos[view] = r.render(face.neutral())
            # a left photo shows the face's left half; the right half's depth comes from the twins
            labels = [label for label in mesh.fp_labels
                      if label != "11.5" and (view == "front" or mesh.fp(label)[0] >= -1e-6)]
            xy = cam.project(np.array([mesh.fp(label) for label in labels]), PHOTO, PHOTO)[:, :2]
            self.points[view] = {label: xy[i].tolist() for i, label in enumerate(labels)}
        self.png = png_bytes(self.photos["front"])
        self.fdp = fdp_from_photos(self.points["front"], self.points["left"], side_view="left",
                                   texture=TextureImage("front.png", "image/png", self.png))

    def photo_colour(self, uv: np.ndarray) -> np.ndarray:
        """The front photo's pixel at texture coordinates (u right, v up)."""
        x = np.clip((uv[:, 0] * PHOTO).astype(int), 0, PHOTO - 1)
        y = np.clip(((1.0 - uv[:, 1]) * PHOTO).astype(int), 0, PHOTO - 1)
        return self.photos["front"][y, x].astype(float)


def png_bytes(image: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(image).save(buf, "PNG")
    return buf.getvalue()


def neutral_stream(n: int = 2) -> FapStream:
    s = FapStream.empty(n)
    s.source_fps = 25.0
    s.timestamps[:] = np.arange(n) / 25.0
    return s


def front_points(face, fdp: Fdp, sender_face) -> list[tuple[str, int]]:
    """The FDP's points on open skin, facing the front camera: (label, vertex).

    Points next to the eyes or teeth (eyelid rims, inner lips) are left out: where
    another part meets the skin, the two heads may show different parts.
    """
    out = []
    for label in fdp.labels:
        clear = True
        for head in (face.mesh, sender_face.mesh):
            v = int(head.fp_vertex[head.fp_index(label)])
            skin = head.part("skin")
            others = np.r_[tuple(np.arange(head.part(name).start, head.part(name).stop)
                                 for name in ("eye_l", "eye_r", "teeth_upper", "teeth_lower", "tongue"))]
            gap = np.linalg.norm(head.vertices[others] - head.vertices[v], axis=1).min()
            normal = vertex_normals(head.vertices, head.triangles["skin"])[v]
            clear &= bool(skin.start <= v < skin.stop and normal[2] > 0.5 and gap > 0.03 * head.height())
        if clear:
            out.append((label, int(face.mesh.fp_vertex[face.mesh.fp_index(label)])))
    return out


def errors_at_points(image: np.ndarray, face, sender: Sender, camera) -> np.ndarray:
    """Largest per-channel |render - photo| (8-bit) at the front-facing feature points."""
    chosen = front_points(face, sender.fdp, sender.face)
    xy = camera.project(face.mesh.vertices[[v for _, v in chosen]], VIEW, VIEW)[:, :2]
    got = image[xy[:, 1].astype(int), xy[:, 0].astype(int)].astype(float)
    uv = sender.fdp.texture_coords[[sender.fdp.index(label) for label, _ in chosen]]
    return np.abs(got - sender.photo_colour(uv)).max(axis=1)


@pytest.fixture(scope="module", params=("procedural", "generic"))
def sender(request) -> Sender:
    return Sender(request.getfixturevalue(f"{request.param}_face"))


def _receiver(request, name: str):
    return request.getfixturevalue(f"{name}_face")


# -- the map ---------------------------------------------------------------------------------

def test_feature_points_get_their_texture_coordinates(sender):
    """Every vertex gets coordinates; at the feature points they are the FDP's own, exactly."""
    face = sender.face.calibrate(sender.fdp)
    sent = bake_fdp_texture(face.mesh, sender.fdp, size=SIZE)
    fdp = sender.fdp
    vertices = [face.mesh.fp_vertex[face.mesh.fp_index(label)] for label in fdp.labels]
    assert sent.vertex_coords.shape == (face.mesh.n_vertices, 2)
    assert np.abs(sent.vertex_coords[vertices] - fdp.texture_coords).max() < 1e-9
    # an orthographic front photo of this very head: the affine part is the camera itself
    assert np.allclose(sent.map.toward, [0.0, 0.0, 1.0], atol=1e-6) and sent.map.residual < 1e-6
    # the front photo covers what the photo baker finds it covers (the face, not the back of the head)
    raster = uv_rasterise(face.mesh, SIZE)
    back = raster.skin & (raster.normal[..., 2] < -0.1)
    photo = bake_texture(sender.face.mesh, PhotoView(sender.photos["front"], sender.points["front"]), size=SIZE)
    agree = (photo.coverage == sent.baked.coverage)[raster.skin].mean()
    assert agree > 0.995 and sent.coverage > 0.2 and not sent.baked.coverage[back].any(), agree
    both = photo.coverage & sent.baked.coverage
    assert np.abs(photo.image.astype(int) - sent.image.astype(int)).max(axis=-1)[both].mean() < 1.0


def test_baked_texture_recovers_the_photographed_colours(sender):
    """Same head: the bake is the field itself where the photo sees it (measured mean 0.25-1.4, p95 1)."""
    face = sender.face.calibrate(sender.fdp)
    sent = bake_fdp_texture(face.mesh, sender.fdp, size=SIZE)
    raster = uv_rasterise(face.mesh, SIZE)
    where = sent.baked.coverage & (raster.normal[..., 2] > 0.5)
    err = np.abs(sent.image.astype(int) - sender.truth.astype(int)).max(axis=-1)[where]
    assert err.mean() <= 2.5 and np.percentile(err, 95) <= 5.0, (err.mean(), np.percentile(err, 95))
    # unseen skin is filled from the seen colours, and off-skin texels repeat their nearest skin texel
    flat = sent.image.reshape(-1, 3)
    assert np.array_equal(flat, flat[raster.nearest.reshape(-1)])


# -- playback --------------------------------------------------------------------------------

@pytest.mark.parametrize("receiver", ["same", "procedural", "generic"])
def test_snapshot_shows_the_photo_at_the_feature_points(request, sender, receiver):
    """snapshot(fdp=...) wears the FDP's texture: measured mean 1.5-1.9, max 3-5 (8-bit) over 26-35 points;
    untextured, mean 113-116."""
    base = sender.face if receiver == "same" else _receiver(request, receiver)
    face = base.calibrate(sender.fdp)
    camera = frame_points(face.mesh.feature_points(), VIEW, VIEW, orthographic=True)
    image = snapshot(neutral_stream(), face=face, fdp=sender.fdp, width=VIEW, height=VIEW, camera=camera,
                     lighting=False)
    err = errors_at_points(image, face, sender, camera)
    assert len(err) >= 20
    assert err.mean() <= 4.0 and err.max() <= 16.0, (err.mean(), err.max())
    # without the texture the same pixels are the plain skin colour, far from the photo's
    plain = snapshot(neutral_stream(), face=face, fdp=sender.fdp, fdp_texture=False, width=VIEW, height=VIEW,
                     camera=camera, lighting=False)
    assert errors_at_points(plain, face, sender, camera).mean() > 40.0


def test_play_and_default_calibration_wear_the_texture(generic_face, tmp_path):
    """play(fdp=...) without a face calibrates the generic head to the FDP and textures it."""
    sender = Sender(generic_face)
    face = generic_face.calibrate(sender.fdp)
    camera = frame_points(face.mesh.feature_points(), VIEW, VIEW, orthographic=True)
    result = play(neutral_stream(3), tmp_path / "frames", fdp=sender.fdp, width=VIEW, height=VIEW, camera=camera,
                  lighting=False)
    assert result.n_frames == 3
    frame = np.asarray(Image.open(sorted((tmp_path / "frames").glob("*.png"))[0]).convert("RGB"))
    err = errors_at_points(frame, face, sender, camera)
    assert err.mean() <= 4.0 and err.max() <= 16.0, (err.mean(), err.max())
    # the three-quarter view shows the photo on the face and a filled side: no background grey on the skin
    quarter = snapshot(neutral_stream(), fdp=sender.fdp, width=256, height=256, view=(35.0, 10.0))
    assert quarter.std(axis=(0, 1)).min() > 10.0


def test_untextured_fdp_and_explicit_texture_are_as_before(procedural_face):
    sender = Sender(procedural_face)
    face = procedural_face.calibrate(sender.fdp)
    options = {"face": face, "width": 96, "height": 96}
    plain = Fdp(sender.fdp.labels, sender.fdp.points)                  # points only: case 1
    before = snapshot(neutral_stream(), **options)
    assert np.array_equal(snapshot(neutral_stream(), fdp=plain, **options), before)
    coords_only = Fdp(sender.fdp.labels, sender.fdp.points, texture_coords=sender.fdp.texture_coords)
    assert np.array_equal(snapshot(neutral_stream(), fdp=coords_only, **options), before)
    assert np.array_equal(snapshot(neutral_stream(), fdp=sender.fdp, fdp_texture=False, **options), before)
    textured = snapshot(neutral_stream(), fdp=sender.fdp, **options)
    assert not np.array_equal(textured, before)
    # an explicit texture wins over the FDP's
    grey = np.full((64, 64, 3), 90, np.uint8)
    with Renderer(face, width=96, height=96, texture=grey) as renderer:
        expected = renderer.render(face.neutral())
    assert np.array_equal(snapshot(neutral_stream(), fdp=sender.fdp, texture=grey, **options), expected)
    assert fdp_skin_texture(face.mesh, plain) is None


# -- bad input -------------------------------------------------------------------------------

def test_bad_fdp_textures_are_located_errors(procedural_face):
    sender = Sender(procedural_face)
    fdp, mesh = sender.fdp, procedural_face.mesh
    no_coords = Fdp(fdp.labels, fdp.points, textures=fdp.textures)
    with pytest.raises(RenderError, match="no texture coordinates") as info:
        bake_fdp_texture(mesh, no_coords, size=64, source="face.fdp")
    assert str(info.value).startswith("face.fdp: texture 'front.png'") and "\n" not in str(info.value)
    broken = Fdp(fdp.labels, fdp.points, texture_coords=fdp.texture_coords,
                 textures=(TextureImage("front.png", "image/png", sender.png[:200]),))
    with pytest.raises(RenderError, match="cannot be decoded") as info:
        bake_fdp_texture(mesh, broken, size=64, source="face.fdp")
    assert str(info.value).startswith("face.fdp: texture 'front.png'")
    mirrored = Fdp(fdp.labels, fdp.points, texture_coords=fdp.texture_coords * [-1.0, 1.0] + [1.0, 0.0],
                   textures=fdp.textures)
    with pytest.raises(RenderError, match="from behind"):
        bake_fdp_texture(mesh, mirrored, size=64)
    few = fdp.subset(("9.3", "2.1", "3.5"))
    with pytest.raises(RenderError, match="at least 4"):
        bake_fdp_texture(mesh, few, size=64)
    with pytest.raises(RenderError, match="no texture image"):
        bake_fdp_texture(mesh, Fdp(fdp.labels, fdp.points), size=64)
    # through the player, the same errors (the FDP was given, so its texture is used)
    with pytest.raises(RenderError, match="no texture coordinates"):
        snapshot(neutral_stream(), face=procedural_face, fdp=no_coords, width=32, height=32)
