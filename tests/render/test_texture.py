"""Photo textures baked onto the skin: synthetic ground truth on both heads, and a real photo.

The ground truth is a colour field over 3D space (so it is continuous across UV
seams), baked into UV space with the module's own rasteriser and rendered unlit
in orthographic front and side views: those renders are the "photos", and their
feature points are the head's own, projected with the same camera. Baking them
back must return the field, up to resampling. Symmetric fields are needed where
the side photo is mirrored onto the far side (the method assumes a symmetric
face); an asymmetric field shows which side a colour came from.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.render.camera import frame_points
from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.renderer import Renderer
from mpeg4fa.render.texture import BakedTexture, PhotoView, UVRaster, align_view, bake_texture, uv_rasterise
from photos import ASTRONAUT, ASTRONAUT_SKIN_PATCH

SIZE = 512      # texture size for the bakes
PHOTO = 384     # synthetic photo size

# labels a person could annotate in each photo
FRONT_LABELS = ("3.5", "3.6", "3.7", "3.8", "3.11", "3.12", "4.1", "4.2", "9.3", "8.1", "8.2", "8.3", "8.4",
                "2.1", "11.1", "10.1", "10.2")
SIDE_LABELS = {
    "left": ("9.3", "2.1", "3.7", "8.3", "10.1", "10.3", "10.5", "11.1", "11.4", "11.6", "2.13", "5.3"),
    "right": ("9.3", "2.1", "3.8", "8.4", "10.2", "10.4", "10.6", "11.1", "11.4", "11.6", "2.14", "5.4"),
}


def symmetric_truth(p: np.ndarray) -> np.ndarray:
    """Smooth colours (0-255) of 3D points, the same at x and -x: wavelengths of 8-12 cm."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    r = 128 + 100 * np.sin(2 * np.pi * y / 90) * np.cos(2 * np.pi * x / 110)
    g = 128 + 100 * np.cos(2 * np.pi * z / 80 + 0.5)
    b = 128 + 100 * np.sin(2 * np.pi * (y + z) / 120 + x * x / 3000)
    return np.clip(np.stack([r, g, b], -1), 0, 255)


def asymmetric_truth(p: np.ndarray) -> np.ndarray:
    """The symmetric field plus a part odd in x (red up, blue down on the face's left)."""
    odd = 60 * np.sin(2 * np.pi * p[..., 0] / 100)
    return np.clip(symmetric_truth(p) + np.stack([odd, 0 * odd, -odd], -1), 0, 255)


class Synthetic:
    """One face, its UV raster, ground-truth textures and the photos rendered from them."""

    def __init__(self, face) -> None:
        self.face, self.mesh = face, face.mesh
        self.raster: UVRaster = uv_rasterise(self.mesh, SIZE)
        self.truth = {name: np.rint(fn(self.raster.position.astype(float))).astype(np.uint8)
                      for name, fn in (("sym", symmetric_truth), ("asym", asymmetric_truth))}
        self.cameras = {view: frame_points(self.mesh.feature_points(), PHOTO, PHOTO, view=view, orthographic=True)
                        for view in ("front", "left", "right")}
        self._photos: dict[tuple[str, str], PhotoView] = {}

    def photo(self, truth: str, view: str) -> PhotoView:
        key = (truth, view)
        if key not in self._photos:
            cam = self.cameras[view]
            with Renderer(self.face, width=PHOTO, height=PHOTO, camera=cam, texture=self.truth[truth],
                          lighting=False) as renderer:
                image = renderer.render(self.face.neutral())
            labels = FRONT_LABELS if view == "front" else SIDE_LABELS[view]
            xy = cam.project(np.array([self.mesh.fp(label) for label in labels]), PHOTO, PHOTO)[:, :2]
            self._photos[key] = PhotoView(image, {label: (x, y) for label, (x, y) in zip(labels, xy)}, view)
        return self._photos[key]

    def near(self, point: np.ndarray, radius: float) -> np.ndarray:
        """Skin texels within ``radius`` mm of a 3D point."""
        return self.raster.skin & (np.linalg.norm(self.raster.position - point, axis=-1) < radius)


def colour_error(baked: BakedTexture, truth: np.ndarray, where: np.ndarray) -> tuple[float, float]:
    """Mean and 95th percentile of the largest per-channel |error| (8-bit units) over texels."""
    err = np.abs(baked.image.astype(int) - truth.astype(int)).max(axis=-1)[where]
    return float(err.mean()), float(np.percentile(err, 95))


@pytest.fixture(scope="module", params=("procedural", "generic"))
def synth(request) -> Synthetic:
    return Synthetic(request.getfixturevalue(f"{request.param}_face"))


# -- synthetic ground truth ------------------------------------------------------------------

def test_alignment_recovers_the_camera(synth):
    """Bounding-box alignment of exact feature points is the orthographic camera itself."""
    for view in ("front", "left", "right"):
        photo = synth.photo("sym", view)
        align = align_view(synth.mesh, photo)
        pts = synth.mesh.feature_points()
        expected = synth.cameras[view].project(pts, PHOTO, PHOTO)[:, :2]
        assert np.allclose(align.project(pts)[:, :2], expected, atol=1e-6)
        assert align.residual < 1e-6


@pytest.mark.parametrize("side", ["left", "right"])
def test_two_photos_recover_the_truth(synth, side):
    """Measured at 512 texels from 384 px photos, both heads: mean 0.7-0.9, p95 2 (8-bit units)."""
    baked = bake_texture(synth.mesh, synth.photo("sym", "front"), synth.photo("sym", side), size=SIZE)
    assert baked.image.shape == (SIZE, SIZE, 3) and baked.image.dtype == np.uint8
    seen = baked.coverage
    assert seen.sum() > 0.7 * synth.raster.skin.sum()
    mean, p95 = colour_error(baked, synth.truth["sym"], seen)
    assert mean <= 2.0 and p95 <= 5.0, (mean, p95)


def test_front_weight_follows_the_normal(synth):
    baked = bake_texture(synth.mesh, synth.photo("sym", "front"), synth.photo("sym", "left"), size=SIZE)
    k = baked.weight_front
    assert k.min() >= 0.0 and k.max() <= 1.0
    assert np.all(k[~baked.coverage] == 0.0)
    nose = synth.near(synth.mesh.fp("9.3"), 3.0) & baked.coverage
    assert nose.any() and k[nose].mean() > 0.9
    # the cheek just in front of the ear, on both sides (the far one through the mirror):
    # its normal is about (0.98, 0, 0.18), so k is about 0.16 on both heads
    for label in ("10.7", "10.8"):
        cheek = synth.near(synth.mesh.fp(label) + [0.0, 0.0, 8.0], 6.0) & baked.coverage
        assert cheek.any() and k[cheek].mean() < 0.25, (label, k[cheek].mean())
    # where both photos see a texel, k is the normal's share of z
    both = baked.coverage & (k > 0.0) & (k < 1.0)
    n = np.abs(synth.raster.normal[both].astype(float))
    assert both.sum() > 0.3 * baked.coverage.sum()
    assert np.allclose(k[both], n[:, 2] / (n[:, 0] + n[:, 2]), atol=1e-5)


def test_side_photo_is_mirrored_onto_the_far_side(synth):
    """With an asymmetric field, side-dominated texels match on the photographed side only."""
    baked = bake_texture(synth.mesh, synth.photo("asym", "front"), synth.photo("asym", "left"), size=SIZE)
    side_only = baked.coverage & (baked.weight_front < 0.1)
    x = synth.raster.position[..., 0]
    near_mean, _ = colour_error(baked, synth.truth["asym"], side_only & (x > 20))
    far_mean, _ = colour_error(baked, synth.truth["asym"], side_only & (x < -20))
    # the far side got the mirror point's colour, which differs by the odd part of the field
    mirror_truth = np.rint(asymmetric_truth(synth.raster.position * [-1.0, 1.0, 1.0]))
    far_vs_mirror = np.abs(baked.image.astype(int) - mirror_truth).max(axis=-1)[side_only & (x < -20)].mean()
    assert near_mean <= 3.0 and far_vs_mirror <= 3.0 and far_mean > 20.0, (near_mean, far_vs_mirror, far_mean)


def test_front_only_recovers_front_facing_texels(synth):
    """Front-only mode, asymmetric field (catches a left/right flip): measured mean 0.3-1.6, p95 1."""
    baked = bake_texture(synth.mesh, synth.photo("asym", "front"), size=SIZE)
    assert set(baked.alignments) == {"front"}
    assert np.all(baked.weight_front[baked.coverage] == 1.0)
    facing = synth.raster.normal[..., 2] > 0.5
    mean, p95 = colour_error(baked, synth.truth["asym"], baked.coverage & facing)
    assert mean <= 3.0 and p95 <= 5.0, (mean, p95)
    # nothing seen faces away from the camera
    assert np.all(synth.raster.normal[..., 2][baked.coverage] > 0.0)


def test_unseen_and_off_skin_texels_are_filled(synth):
    baked = bake_texture(synth.mesh, synth.photo("sym", "front"), size=SIZE)
    skin, cover = synth.raster.skin, baked.coverage
    unseen = skin & ~cover
    assert unseen.any()
    # a fill is a weighted mean of seen colours: inside their range, channel by channel
    lo, hi = baked.image[cover].min(axis=0), baked.image[cover].max(axis=0)
    assert np.all((baked.image[unseen] >= lo) & (baked.image[unseen] <= hi))
    # off the skin, each texel repeats its nearest skin texel (no background for mip-maps to blend in)
    flat = baked.image.reshape(-1, 3)
    assert np.array_equal(flat, flat[synth.raster.nearest.reshape(-1)])


# -- bad input -------------------------------------------------------------------------------

def test_bad_input_says_what_to_fix(procedural_face):
    mesh = procedural_face.mesh
    image = np.zeros((64, 64, 3), np.uint8)
    with pytest.raises(RenderError, match="uint8"):
        PhotoView(image.astype(np.float32), {}, "front")
    with pytest.raises(RenderError, match=r"\(H, W, 3\)"):
        PhotoView(image[..., 0], {}, "front")
    with pytest.raises(RenderError, match="view"):
        PhotoView(image, {}, "top")
    with pytest.raises(RenderError, match="finite"):
        PhotoView(image, {"9.3": (np.nan, 3.0)}, "front")
    with pytest.raises(RenderError, match="at least 2"):
        bake_texture(mesh, PhotoView(image, {}, "front"), size=64)
    with pytest.raises(RenderError, match="at least 2"):
        bake_texture(mesh, PhotoView(image, {"9.3": (30.0, 30.0)}, "front"), size=64)
    with pytest.raises(RenderError, match="12.1"):
        bake_texture(mesh, PhotoView(image, {"9.3": (30.0, 30.0), "12.1": (30.0, 50.0)}, "front"), size=64)
    with pytest.raises(RenderError, match="no distance"):
        bake_texture(mesh, PhotoView(image, {"3.5": (30.0, 30.0), "3.6": (30.0, 30.0)}, "front"), size=64)
    with pytest.raises(RenderError, match="wrong way"):   # the pupils swapped: a mirrored photo
        bake_texture(mesh, PhotoView(image, {"3.5": (20.0, 30.0), "3.6": (40.0, 30.0)}, "front"), size=64)
    with pytest.raises(RenderError, match="wrong way"):   # chin above the nose
        bake_texture(mesh, PhotoView(image, {"9.3": (30.0, 40.0), "2.1": (30.0, 20.0)}, "front"), size=64)
    with pytest.raises(RenderError, match="wrong way"):   # a 'left' photo whose nose points right
        side = PhotoView(image, {"9.3": (50.0, 30.0), "10.1": (20.0, 20.0)}, "left")
        bake_texture(mesh, PhotoView(image, {"3.5": (40.0, 30.0), "3.6": (20.0, 30.0)}, "front"), side, size=64)
    front = PhotoView(image, {"3.5": (40.0, 30.0), "3.6": (20.0, 30.0)}, "front")
    with pytest.raises(RenderError, match="side photo"):
        bake_texture(mesh, front, front, size=64)
    with pytest.raises(RenderError, match="view='front'"):
        bake_texture(mesh, PhotoView(image, {}, "left"), size=64)
    with pytest.raises(RenderError, match="texture size"):
        bake_texture(mesh, front, size=4)


def test_one_axis_degenerate_borrows_the_other_scale(procedural_face):
    """Two points on the midline span no width: the horizontal scale is the vertical one."""
    mesh = procedural_face.mesh
    image = np.zeros((200, 200, 3), np.uint8)
    nose, chin = mesh.fp("9.3"), mesh.fp("2.1")
    align = align_view(mesh, PhotoView(image, {"9.3": (100.0, 60.0), "2.1": (100.0, 140.0)}, "front"))
    assert align.scale[0] == pytest.approx(align.scale[1]) == pytest.approx(80.0 / (nose[1] - chin[1]))
    assert np.allclose(align.project(np.array([nose, chin]))[:, :2], [[100, 60], [100, 140]])


# -- a real photo ----------------------------------------------------------------------------

def test_astronaut_photo_on_the_generic_head(generic_face):
    """Front-only bake of a real portrait: her colours land on the right parts of the head."""
    from skimage import data  # slow to import: only here

    photo = data.astronaut()
    mesh = generic_face.mesh
    baked = bake_texture(mesh, PhotoView(photo, ASTRONAUT, "front"), size=SIZE)
    assert baked.alignments["front"].residual < 6.0   # pixels; she smiles, the head does not
    raster = uv_rasterise(mesh, SIZE)
    colours = baked.image.astype(float)

    def around(label: str, radius: float) -> np.ndarray:
        sel = raster.skin & (np.linalg.norm(raster.position - mesh.fp(label), axis=-1) < radius)
        assert sel.sum() >= 5, label
        return colours[sel].mean(axis=0)

    skin = photo[ASTRONAUT_SKIN_PATCH].reshape(-1, 3).astype(float).mean(axis=0)
    cheeks = [around(label, 6.0) for label in ("5.1", "5.2")]
    for cheek in cheeks:                      # measured: within 6-9 of her cheek patch
        assert np.abs(cheek - skin).max() < 25.0, (cheek, skin)
    luminance = np.array([0.299, 0.587, 0.114])
    cheek_lum = min(c @ luminance for c in cheeks)
    for pupil in ("3.5", "3.6"):              # eyelids and lashes around the eyeballs: 24-55 darker
        assert around(pupil, 8.0) @ luminance < cheek_lum - 15.0
    redness = [c[0] / c[1] for c in cheeks]   # measured: lips R/G 1.34, cheeks 1.19-1.22
    for lip in ("8.1", "8.2"):
        c = around(lip, 4.0)
        assert c[0] / c[1] > max(redness) + 0.06, (lip, c, redness)
    assert around("11.1", 5.0) @ luminance < cheek_lum - 30.0   # her hair on the forehead's top
    with Renderer(generic_face, width=128, height=128, texture=baked.image) as renderer:
        image = renderer.render(generic_face.neutral())
    centre = image[40:90, 44:84].reshape(-1, 3).astype(float).mean(axis=0)
    assert centre[0] > centre[2] + 20      # a warm face, not the background's blue-grey


def test_unseen_texels_take_their_mirror_images_colour():
    """A turned face's far cheek wears its near one (x -> -x), but not the near side's grazing edge."""
    from mpeg4fa.render.texture import MIRROR_MARGIN, _mirror_unseen
    x, y = np.meshgrid(np.linspace(-100, 100, 201), np.linspace(-100, 100, 201))
    points = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    seen = points[:, 0] > 0                                   # the photo saw the face's left (+x) only
    colours = np.zeros((len(points), 3), np.float32)
    colours[seen] = np.c_[points[seen, 0], points[seen, 1] + 100, np.full(seen.sum(), 50.0)]
    out, mirrored = _mirror_unseen(points, colours, seen)
    margin = MIRROR_MARGIN * 200
    far = points[:, 0] < -margin - 1
    assert mirrored[far].all() and not mirrored[seen].any()
    assert np.allclose(out[far, 0], -points[far, 0]) and np.allclose(out[far, 1], points[far, 1] + 100)
    assert not mirrored[(points[:, 0] <= 0) & (points[:, 0] > -margin + 1)].any()   # the edge is not copied
    assert np.array_equal(out[seen], colours[seen])
