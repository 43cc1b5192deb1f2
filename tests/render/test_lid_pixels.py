"""What the viewer sees of the eyes as the lids close (generic head; unlit, colour-coded materials).

Skin and mouth are drawn pure red, the sclera blue, the iris green, the pupil cyan: any pixel
with little red and some green or blue is eyeball. At the value that brings a lid point to the
height of the opposite one the eye is covered, front and three-quarter; at half that value half
of the iris is.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import EXACT_DEFORMERS, face_under
from mpeg4fa.render import Materials, Renderer, frame_points

pytestmark = pytest.mark.usefixtures("generic_head_installed")

CODED = Materials().with_colours(skin=(1, 0, 0), mouth=(1, 0, 0), lips=(1, 0, 0), sclera=(0, 0, 1),
                                 iris=(0, 1, 0), pupil=(0, 1, 1), background=(1, 1, 0))
EYE_POINTS = ("3.5", "3.6", "3.7", "3.8", "3.11", "3.12", "4.5", "4.6", "3.3", "3.4")


def _eyeball(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return (r < 80) & (g + b > 120)


def _iris(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return (r < 80) & (g > 120)


@pytest.fixture(scope="module", params=[(view, d) for d in EXACT_DEFORMERS for view in ("front", "three-quarter")],
                ids=lambda p: f"{p[1]}-{p[0]}")
def eyes(request):
    view, deformer = request.param
    face = face_under(request, "generic", deformer)
    points = np.array([face.mesh.fp(label) for label in EYE_POINTS])
    camera = frame_points(points, 320, 160, view=view, margin=0.3)
    with Renderer(face, width=320, height=160, lighting=False, materials=CODED, camera=camera) as r:
        yield face, r


def _closing(face, point: str, opposite: str) -> float:
    return (face.mesh.fp(point)[1] - face.mesh.fp(opposite)[1]) / face.fapu.unit("IRISD")


def test_open_eyes_show_sclera_and_iris(eyes):
    face, r = eyes
    image = r.render(face.neutral())
    assert _eyeball(image).sum() > 400 and _iris(image).sum() > 150


def test_upper_lids_close_the_eyes(eyes):
    face, r = eyes
    close = _closing(face, "3.1", "3.3")
    assert close == pytest.approx(1024, rel=0.02)  # the lid opening is IRISD0 on a neutral face
    shut = r.render(face.deform({19: close, 20: _closing(face, "3.2", "3.4")}))
    assert _eyeball(shut).sum() == 0


def test_half_closed_lids_cover_half_the_iris(eyes):
    face, r = eyes
    open_iris = _iris(r.render(face.neutral())).sum()
    half = _iris(r.render(face.deform({19: _closing(face, "3.1", "3.3") / 2,
                                       20: _closing(face, "3.2", "3.4") / 2}))).sum()
    assert 0.35 < half / open_iris < 0.65, half / open_iris


def test_lower_lids_close_the_eyes(eyes):
    face, r = eyes
    shut = r.render(face.deform({21: _closing(face, "3.1", "3.3"), 22: _closing(face, "3.2", "3.4")}))
    assert _eyeball(shut).sum() == 0


def test_idle_blinks_shut_the_eyes(eyes):
    from mpeg4fa.speech.timeline import frame_times, idle_track

    face, r = eyes
    times = frame_times(12.0, 25.0)
    track = idle_track(times, seed=7, head=False)
    blinking = np.flatnonzero(track[:, 18] > 0)
    assert len(blinking) >= 2
    peak = blinking[np.argmax(track[blinking, 18])]
    assert _eyeball(r.render(face.pose_values(track[peak]))).sum() == 0
    assert _eyeball(r.render(face.pose_values(track[0]))).sum() > 400
