"""Brows drawn as hairs (render/brows.py): close up they show hairs that rise at the inner end and lie flat at the
outer one, not one set of even stripes; from afar they read as dark as a brow; and only the skin's triangles about
the brows pay for them.

The brow's pixels come from the same pose drawn unlit with the brows coded yellow (weight over about 0.8); the lit
picture is read inside that mask.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from mpeg4fa.render import Materials, Renderer, frame_points
from mpeg4fa.render.brows import ALONG, about_the_brows, brow_hair_image
from mpeg4fa.render.details import brow_coordinates

CODED = Materials().with_colours(skin=(0.5, 0.5, 0.5), lips=(0.5, 0.5, 0.5), brows=(1, 1, 0))
CLOSE = 512  # px across the left brow, about 14 px a mm: a hair (0.18 mm at its root) is 2-3 px wide


def _luma(image: np.ndarray) -> np.ndarray:
    return image.astype(float) @ np.array([0.299, 0.587, 0.114])


def _brow_mask(face, camera, size: int) -> np.ndarray:
    with Renderer(face, width=size, height=size, lighting=False, materials=CODED, camera=camera) as r:
        flat = r.render(face.neutral()).astype(int)
    return (flat[..., 0] > 200) & (flat[..., 2] < 60)


def _hair_angle(luma: np.ndarray, mask: np.ndarray) -> float:
    """Degrees above the horizontal (image x to the right, y up) of the strokes inside ``mask``: the direction of
    least change of the structure tensor."""
    gx, gy = ndimage.sobel(luma, axis=1), -ndimage.sobel(luma, axis=0)
    inner = ndimage.binary_erosion(mask, iterations=3)  # the brow's outline is an edge of its own
    jxx, jyy, jxy = (gx * gx)[inner].sum(), (gy * gy)[inner].sum(), (gx * gy)[inner].sum()
    gradient = 0.5 * np.degrees(np.arctan2(2.0 * jxy, jxx - jyy))
    return float((gradient + 90.0 + 90.0) % 180.0 - 90.0)  # strokes run across the strongest gradient


@pytest.fixture(scope="module")
def close_up(generic_face):
    """The left brow close up, lit, its mask, and the columns of its inner and outer ends; mirrored where needed so
    that the outer end is to the right."""
    face = generic_face
    camera = frame_points(np.array([face.mesh.fp(k) for k in ("4.1", "4.3", "4.5")]), CLOSE, CLOSE, margin=0.1)
    with Renderer(face, width=CLOSE, height=CLOSE, samples=4, camera=camera) as r:
        lit = _luma(r.render(face.neutral()))
    mask = _brow_mask(face, camera, CLOSE)
    inner, outer = camera.project(np.array([face.mesh.fp("4.1"), face.mesh.fp("4.5")]), CLOSE, CLOSE)[:, 0]
    if outer < inner:
        lit, mask, inner, outer = lit[:, ::-1], mask[:, ::-1], CLOSE - 1 - inner, CLOSE - 1 - outer
    return lit, mask, inner, outer


def test_brow_hairs_rise_at_the_inner_end_and_lie_flat_at_the_outer(close_up):
    """The old strokes were one sawtooth across the brow, the same slant from end to end (measured -55 and -59
    degrees); hairs rise steeply at the inner end and lie nearly along the brow outward (degrees above the horizontal,
    toward the outer end; measured 60 and -16, where the brow itself turns down)."""
    lit, mask, inner, outer = close_up
    share = (np.arange(lit.shape[1])[None, :] - inner) / (outer - inner)
    a_inner = _hair_angle(lit, mask & (share >= 0.03) & (share <= 0.33))
    a_outer = _hair_angle(lit, mask & (share >= 0.67) & (share <= 0.97))
    assert a_inner - a_outer > 25.0, (a_inner, a_outer)
    assert a_inner > 35.0 and abs(a_outer) < 25.0, (a_inner, a_outer)


def test_brow_hairs_show_close_up(close_up):
    """Strokes of their own against the brow's tint: fine-scale contrast inside the brow (luminance less its 9 px
    mean: std 6.0; the old sawtooth 3.6)."""
    lit, mask, _, _ = close_up
    fine = lit - ndimage.uniform_filter(lit, 9)
    inner = ndimage.binary_erosion(mask, iterations=3)
    assert fine[inner].std() > 5.0, fine[inner].std()


def test_brows_read_dark_from_afar(generic_face):
    """The whole head at 256 px (a brow some 30 px long): the brow's mean under half the forehead's luminance (measured
    79 against 182; the old strokes 76)."""
    face = generic_face
    camera = frame_points(face.mesh.feature_points(), 256, 256)
    with Renderer(face, width=256, height=256, samples=4, camera=camera) as r:
        lit = _luma(r.render(face.neutral()))
    mask = _brow_mask(face, camera, 256)
    brow_top = np.flatnonzero(mask.any(axis=1))[0]
    cols = np.flatnonzero(mask.any(axis=0))
    forehead = lit[brow_top - 12:brow_top - 6, cols.min():cols.max() + 1]
    assert mask.sum() > 40
    assert lit[mask].mean() < 0.5 * forehead.mean(), (lit[mask].mean(), forehead.mean())


def test_the_hair_image_covers_the_brow_and_is_bare_at_its_edges():
    image = brow_hair_image()
    assert image.dtype == np.uint8 and image.shape == (256, 1024)
    assert not image[[0, -1]].any() and not image[:, [0, -1]].any()  # a lookup clamped there finds no hair
    assert 0.35 < image.mean() / 255.0 < 0.6  # two layers of hairs, some crossing


def test_only_the_triangles_about_the_brows_draw_them(generic_face):
    """The brow variant draws exactly the skin's triangles about the brows (a small share of the skin), every other
    triangle is drawn once by another variant or by the mouth's finer patch, and every skin vertex the shader can
    give a brow (within the widest brow and its stray hairs, :data:`.brows.HEIGHT`) lies on one of them."""
    face = generic_face
    with Renderer(face, width=64, height=64) as r:
        drawn = np.frombuffer(r.index.read(), np.uint32).reshape(-1, 3)
        # the mouth's range is drawn finer (render/refine.py)
        ranges = [*r.face_ranges, r.brow_range, r.eye_range, r.mouth_range]
        brow_first, brow_count = r.brow_range
        skin_tris = r.layout.indices[:len(face.mesh.triangles["skin"])]
    cover = np.zeros(3 * len(drawn), int)
    for first, count in ranges:
        cover[first:first + count] += 1
    assert (cover == 1).all()  # the draws tile the index buffer
    chosen = about_the_brows(r.layout.detail, skin_tris)
    block = drawn[brow_first // 3:(brow_first + brow_count) // 3]
    assert sorted(map(tuple, block)) == sorted(map(tuple, skin_tris[chosen]))
    assert 0 < chosen.mean() < 0.1, chosen.mean()
    detail = brow_coordinates(face.mesh, face.mesh.vertices)
    on_brow = (detail[:, 0] >= ALONG[0]) & (detail[:, 0] <= ALONG[1]) & (detail[:, 1] >= -4.65) & (detail[:, 1] <= 3.85)
    tris = np.asarray(face.mesh.triangles["skin"])
    in_block = np.zeros(face.mesh.n_vertices, bool)
    in_block[tris[about_the_brows(detail, tris)].ravel()] = True
    assert on_brow.any() and not (on_brow & ~in_block & np.isin(np.arange(len(detail)), tris)).any()
