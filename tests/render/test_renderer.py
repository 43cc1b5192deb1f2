"""The renderer on both test faces: determinism, goldens, eyes, mouth, sizes, errors.

Golden images live in ``golden/``; after an intended change of the look, rewrite
them with ``MPEG4FA_UPDATE_GOLDENS=1 pytest tests/render/test_renderer.py`` and
look at them before committing. llvmpipe output may differ slightly between CPUs
(vector width), so goldens are compared with a tolerance.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.render import Materials, Renderer, RenderError, frame_points
from mpeg4fa.render.context import describe_context

GOLDEN = Path(__file__).with_name("golden")
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
    """A camera framed on a few feature points; unlit for geometric checks (no highlights)."""
    pts = np.array([face.mesh.fp(label) for label in part_labels])
    return Renderer(face, width=size, height=size, lighting=lighting,
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


def test_open_jaw_shows_the_mouth_interior(generic_face):
    """(The procedural head has no mouth slit: its lips stretch, so this is the generic head's.)"""
    face = generic_face
    with _close_up(face, ["8.1", "8.2", "8.3", "8.4", "2.1"], size=128, margin=0.3) as r:
        closed = r.render(face.neutral())
        pose = face.deform({3: 700})
        opened = r.render(pose)
        top, bottom = r.camera.project(pose.feature_points[[face.mesh.fp_labels.index(x) for x in ("2.2", "2.3")]],
                                       128, 128)[:, :2]
    x = int(round((top[0] + bottom[0]) / 2))
    rows = slice(int(np.ceil(top[1])) + 1, int(np.floor(bottom[1])) - 1)
    assert rows.stop - rows.start >= 3
    gap_open, gap_closed = opened[rows, x - 1:x + 2].astype(float), closed[rows, x - 1:x + 2].astype(float)
    skin = np.array(Materials().skin.colour) * 255
    # inside the opened lips: darker and redder than the lit skin there before (mouth, tongue, teeth shadow)
    assert gap_open.mean() < gap_closed.mean() - 15
    assert np.abs(gap_open.mean(axis=(0, 1)) - skin).sum() > 40


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
    path = GOLDEN / f"{face_name}-{pose_name}.png"
    if os.environ.get("MPEG4FA_UPDATE_GOLDENS"):
        Image.fromarray(image).save(path)
    golden = np.asarray(Image.open(path).convert("RGB")).astype(int)
    diff = np.abs(image.astype(int) - golden)
    assert diff.mean() < 1.0, f"{path.name}: mean difference {diff.mean():.2f}"
    assert (diff.max(axis=2) > 24).mean() < 0.005, f"{path.name}: too many pixels differ"


def test_errors(procedural_face, generic_face):
    with pytest.raises(RenderError, match="size"):
        Renderer(procedural_face, width=0, height=10)
    with pytest.raises(RenderError, match="samples"):
        Renderer(procedural_face, width=16, height=16, samples=1000)
    with Renderer(procedural_face, width=16, height=16) as r:
        with pytest.raises(RenderError, match="vertices"):
            r.render(generic_face.neutral())
