"""The renderer on both test faces: determinism, goldens, eyes, mouth, sizes, errors.

Golden images live in ``golden/``; after an intended change of the look, rewrite
them with ``MPEG4FA_UPDATE_GOLDENS=1 pytest tests/render/test_renderer.py`` and
look at them before committing. llvmpipe output may differ slightly between CPUs
(vector width), so goldens are compared with a tolerance.
"""
from __future__ import annotations


import numpy as np
import pytest

from mpeg4fa.render import Materials, Renderer, RenderError, frame_points
from mpeg4fa.render.context import describe_context
from goldens import assert_matches_golden

POSES = {
    "neutral": {},
    "open-joy-gaze": {3: 500, 12: 200, 13: 200, 23: -15000, 24: -15000, 48: 4000},
}


def _dark(image: np.ndarray, level: int = 30) -> np.ndarray:
    return image.max(axis=2) < level


def test_context_is_headless_gl():
    info = describe_context()
    assert info["GL_VERSION"] and info["GL_RENDERER"]


def test_render_is_deterministic_and_reads_into_preallocated_arrays(face):
    pose = face.deform({3: 300, 19: 200, 20: 200})
    with Renderer(face, width=96, height=80) as r:
        a = r.render(pose)
        out = np.zeros((80, 96, 3), np.uint8)
        b = r.render(pose, out=out)
        assert b is out and a.shape == (80, 96, 3) and a.dtype == np.uint8
        np.testing.assert_array_equal(a, b)
    with Renderer(face, width=96, height=80) as r2:
        np.testing.assert_array_equal(r2.render(pose), a)


def test_head_is_framed_from_the_feature_points(face):
    with Renderer(face, width=128, height=128) as r:
        image = r.render(face.neutral())
        background = np.array(Materials().background) ** (1 / 1.0) * 255
        head = np.abs(image.astype(float) - background.round()).max(axis=2) > 12
        rows, cols = np.flatnonzero(head.any(axis=1)), np.flatnonzero(head.any(axis=0))
        # the head fills most of the frame and is centred left/right
        assert rows[0] < 30 and cols[-1] - cols[0] > 50
        assert abs((cols[0] + cols[-1]) / 2 - 63.5) < 6
        # every feature point projects inside the image
        px = r.camera.project(face.neutral().feature_points, 128, 128)
        assert (px[:, :2] >= 0).all() and (px[:, :2] < 128).all()


def _close_up(face, part_labels: list[str], size: int = 128, margin: float = 0.6, lighting: bool = True) -> Renderer:
    """A camera framed on a few feature points; unlit for geometric checks (no highlights); no lashes,
    so that the dark pixels are the pupils."""
    pts = np.array([face.mesh.fp(label) for label in part_labels])
    return Renderer(face, width=size, height=size, lighting=lighting, lashes=False,
                    camera=frame_points(pts, size, size, margin=margin))


def test_pupil_follows_faps_29_and_30(generic_face):
    face = generic_face
    with _close_up(face, ["3.5", "3.6", "3.7", "3.8", "3.11", "3.12"], size=512, lighting=False) as r:
        half = r.width // 2

        def pupils(values):
            dark = _dark(r.render(face.deform(values)), level=40)
            # image left = the face's right eye (FAP 30); image right = the face's left eye (FAP 29)
            return dark[:, :half].sum(), dark[:, half:].sum()
        right0, left0 = pupils({})
        right1, left1 = pupils({29: 200})
        right2, left2 = pupils({30: -100})
    assert left0 > 40 and right0 > 40 and abs(left0 - right0) <= 0.1 * left0
    # 200 x IRISD0/1024 widens the left pupil from IRISD0/3 to 0.53 IRISD0: area x 2.5;
    # -100 narrows the right one to 0.24 IRISD0: area x 0.5
    assert 2.2 < left1 / left0 < 2.8 and right1 == right0
    assert 0.4 < right2 / right0 < 0.62 and left2 == left0


def test_pupil_sits_on_the_gaze_axis(generic_face):
    face = generic_face
    with _close_up(face, ["3.5", "3.6", "3.7", "3.8", "3.11", "3.12"], size=256, lighting=False) as r:
        for values in ({}, {23: 20000, 24: 20000}, {25: -15000, 26: -15000}):
            pose = face.deform(values)
            dark = _dark(r.render(pose))
            front = pose.vertices[[pose.parts["eye_r"].start, pose.parts["eye_l"].start]]
            expected = r.camera.project(front, 256, 256)[:, :2]
            for (ex, ey), side in zip(expected, (slice(0, 128), slice(128, 256))):
                ys, xs = np.nonzero(dark[:, side])
                centroid = np.array([xs.mean() + side.start + 0.5, ys.mean() + 0.5])
                assert np.hypot(*(centroid - (ex, ey))) < 2.0, (values, centroid, ex, ey)


def test_open_jaw_shows_teeth_tongue_and_mouth_interior(generic_face):
    """Unlit, with a pure colour per material: what the opened lips reveal is teeth, tongue and
    the dark oral cavity. (The procedural head has no mouth slit: its lips stretch, so this is the
    generic head's; tests/render/test_mouth.py checks where each of them is.)"""
    face = generic_face
    marked = Materials().with_colours(teeth=(0, 0, 1), tongue=(0, 1, 0), cavity=(1, 0, 0))
    pts = np.array([face.mesh.fp(label) for label in ("8.1", "8.2", "8.3", "8.4", "2.1")])
    with Renderer(face, width=160, height=160, lighting=False, materials=marked,
                  camera=frame_points(pts, 160, 160, margin=0.3)) as r:
        closed = r.render(face.neutral())
        pose = face.deform({3: 700})
        opened = r.render(pose)
        corners = r.camera.project(pose.feature_points[[face.mesh.fp_labels.index(x)
                                                        for x in ("2.2", "2.3", "2.4", "2.5")]], 160, 160)[:, :2]
    top, bottom, left, right = corners[0, 1], corners[1, 1], corners[:, 0].min(), corners[:, 0].max()
    gap = np.s_[int(np.ceil(top)) + 1:int(np.floor(bottom)) - 1, int(left) + 4:int(right) - 4]

    def pure(image, channel):
        others = [c for c in range(3) if c != channel]
        return ((image[..., channel] > 200) & (image[..., others] < 40).all(axis=-1))

    shut = sum(pure(closed[gap], c).mean() for c in range(3))
    found = {name: pure(opened[gap], c).mean() for name, c in (("mouth", 0), ("tongue", 1), ("teeth", 2))}
    assert found["teeth"] > 0.02 and found["tongue"] > 0.02, found
    assert sum(found.values()) > 0.6 and shut < 0.05, (found, shut)


@pytest.mark.parametrize("size", [(64, 64), (320, 240), (200, 360)])
def test_any_size(procedural_face, size):
    w, h = size
    with Renderer(procedural_face, width=w, height=h) as r:
        image = r.render(procedural_face.neutral())
    assert image.shape == (h, w, 3)
    assert image.std() > 10


def test_antialiasing_smooths_edges_only(procedural_face):
    pose = procedural_face.neutral()
    with Renderer(procedural_face, width=128, height=128) as plain, \
            Renderer(procedural_face, width=128, height=128, samples=4) as smooth:
        a, b = plain.render(pose).astype(int), smooth.render(pose).astype(int)
    diff = np.abs(a - b).max(axis=2)
    assert 0 < (diff > 8).mean() < 0.08  # edges change, the bulk does not
    # anti-aliased edges have intermediate values: more distinct colours
    assert len(np.unique(b.reshape(-1, 3), axis=0)) > len(np.unique(a.reshape(-1, 3), axis=0))


def test_unlit_draws_the_base_colour(procedural_face):
    m = Materials().with_colours(skin=(0.25, 0.5, 0.75))
    with Renderer(procedural_face, width=64, height=64, lighting=False, materials=m) as r:
        image = r.render(procedural_face.neutral())
    centre = image[28:36, 28:36].reshape(-1, 3)
    np.testing.assert_allclose(np.median(centre, axis=0), [64, 128, 191], atol=1.5)


@pytest.mark.parametrize("face_name", ["procedural", "generic"])
@pytest.mark.parametrize("pose_name", sorted(POSES))
def test_golden_images(request, face_name, pose_name):
    face = request.getfixturevalue(f"{face_name}_face")
    with Renderer(face, width=128, height=128, samples=4) as r:
        image = r.render(face.deform(POSES[pose_name]))
    assert_matches_golden(image, f"{face_name}-{pose_name}.png")


def test_errors(procedural_face, generic_face):
    with pytest.raises(RenderError, match="size"):
        Renderer(procedural_face, width=0, height=10)
    with pytest.raises(RenderError, match="samples"):
        Renderer(procedural_face, width=16, height=16, samples=1000)
    with Renderer(procedural_face, width=16, height=16) as r:
        with pytest.raises(RenderError, match="vertices"):
            r.render(generic_face.neutral())


def test_renderers_share_the_program_without_leaking_settings(procedural_face):
    """Two renderers with other materials, cameras and lighting, drawn in turn, each as if alone."""
    pose = procedural_face.deform({3: 200})
    kinds = [dict(), dict(materials=Materials().with_colours(skin=(0.2, 0.6, 0.3)), view="left", lighting=False)]
    alone = []
    for kind in kinds:
        with Renderer(procedural_face, width=48, height=48, **kind) as r:
            alone.append(r.render(pose))
    a, b = (Renderer(procedural_face, width=48, height=48, **kind) for kind in kinds)
    with a, b:
        for _ in range(2):
            np.testing.assert_array_equal(a.render(pose), alone[0])
            np.testing.assert_array_equal(b.render(pose), alone[1])
    assert np.abs(alone[0].astype(int) - alone[1]).max() > 50


def test_texture_must_be_an_8_bit_rgb_image(procedural_face):
    with pytest.raises(RenderError, match="uint8"):
        Renderer(procedural_face, width=16, height=16, texture=np.zeros((8, 8)))
    with pytest.raises(RenderError, match="uint8"):
        Renderer(procedural_face, width=16, height=16, texture=np.ones((8, 8, 3)))
    with Renderer(procedural_face, width=32, height=32, lighting=False,
                  texture=np.full((8, 8, 3), (10, 200, 30), np.uint8)) as r:
        centre = r.render(procedural_face.neutral())[12:20, 12:20].reshape(-1, 3)
    np.testing.assert_allclose(np.median(centre, axis=0), (10, 200, 30), atol=2)
