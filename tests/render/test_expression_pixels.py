"""What the expressions show in pixels (issue 29): disgust wrinkles the nose, visibly.

The wrinkle is drawn by the shader on the skin over the upper nose, as strong as the pose draws
the nose tip toward the bridge (:func:`mpeg4fa.face.looks.nose_wrinkle`); measured as the ripple of
brightness down the bridge (what is left after a 15-pixel running mean), under both deformers.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import face_under
from mpeg4fa.render import Renderer, frame_points
from mpeg4fa.spec import EXPRESSION_PROFILES

SIZE = 200


def _bridge_ripple(r: Renderer, values) -> float:
    """Brightness ripple (grey levels, RMS about a running mean) down the nose bridge above the bump."""
    face = r.face
    pose = face.deform(np.asarray(values, float))
    image = r.render(pose).astype(float).mean(axis=2)
    idx = [face.mesh.fp_index(label) for label in ("9.12", "4.1", "4.2")]
    (bx, by), (lx, ly), (rx, ry) = r.camera.project(pose.feature_points[idx], SIZE, SIZE)[:, :2]
    top, bottom = int(min(ly, ry)), int(by)
    x0 = int(bx)
    rows = np.arange(top, bottom)
    # a strip left and right of the midline (the creases run across both sides of the bridge)
    profile = image[top:bottom, x0 - 6:x0 + 7].mean(axis=1)
    smooth = np.convolve(np.pad(profile, 7, mode="edge"), np.ones(15) / 15, mode="valid")
    return float(np.sqrt(np.mean((profile - smooth)[3:-3] ** 2)))


@pytest.mark.parametrize("deformer", ["fap", "arkit"])
def test_disgust_wrinkles_the_nose(request, deformer):
    face = face_under(request, "generic", deformer)
    pts = np.array([face.mesh.fp(label) for label in ("4.1", "4.2", "9.12", "9.3")])
    with Renderer(face, width=SIZE, height=SIZE, samples=4, camera=frame_points(pts, SIZE, SIZE)) as r:
        neutral, disgust, joy = (_bridge_ripple(r, EXPRESSION_PROFILES[name])
                                 for name in ("neutral", "disgust", "joy"))
    assert disgust >= 3.0 and disgust >= 3 * neutral, (neutral, disgust)
    assert joy <= 1.5 * neutral + 0.5, "no wrinkle where the nose is not drawn up"
