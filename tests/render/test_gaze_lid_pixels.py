"""What the viewer sees of the iris as the eyes look up and down (issue 29 item 4; generic head, every exact deformer).

Drawn unlit with colour-coded materials (skin red, sclera blue, iris green, pupil cyan). Per eye:

* the **upper lid's share of the iris**: pixels of the iris disc (its rim projected from the posed eyeball,
  IRISD0 across, as the shader draws it) in the disc's upper half that show no iris, over the disc's pixels;
* the **sclera above the iris**: in the middle half of the iris's columns, sclera pixels above the topmost
  iris pixel, per column (a band of white between the upper lid and the iris).

The generic head's open upper lid sits at the top of the iris (2 % of it covered, 0.75 px of sclera above,
front). Before the lids rode on the pitch, looking up 20 deg hid 48 % of the iris under the upper lid and
looking down 20 deg bared 17.3 px of sclera per column above it; then 4 % and 0.1 px, and since the upper lid
closes by its front edge (mpeg4fa/face/lids.py, FOLLOW) 3.5 % and at most 1.1 px (looking down 10 deg).
"""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image, ImageDraw

from conftest import EXACT_DEFORMERS, face_under
from mpeg4fa.render import Materials, Renderer, frame_points
from mpeg4fa.spec import ANGLE_UNIT, FAPS

pytestmark = pytest.mark.usefixtures("generic_head_installed")

W, H = 480, 200
CODED = Materials().with_colours(skin=(1, 0, 0), mouth=(1, 0, 0), lips=(1, 0, 0), sclera=(0, 0, 1),
                                 iris=(0, 1, 0), pupil=(0, 1, 1), background=(1, 1, 0))
EYE_POINTS = ("3.5", "3.6", "3.7", "3.8", "3.11", "3.12", "4.5", "4.6", "3.3", "3.4")
EYES = (("eye_l", "l-eye"), ("eye_r", "r-eye"))
FULL_DEG = float(np.degrees(FAPS[24].i_max * FAPS[24].quant_step * ANGLE_UNIT))  # FAPs 25/26's full I range
SHARE_TOLERANCE = 0.06
"""How far the upper lid's share of the iris may move from straight gaze's at 20 deg: a band about 0.6 mm
high at the top of the 11.5 mm iris (a lid margin within about a lash's thickness of where it was); before
the follow the share moved by 0.45 looking up."""
SCLERA_ROWS = 1.5
"""Sclera above the iris, px per column, allowed when looking down: the rim where the lid's edge and the
iris's top share pixels (0.75 at straight gaze); before the follow, 17.3 at 20 deg down."""


@pytest.fixture(scope="module", params=[(view, d) for d in EXACT_DEFORMERS for view in ("front", "three-quarter")],
                ids=lambda p: f"{p[1]}-{p[0]}")
def eyes(request):
    view, deformer = request.param
    face = face_under(request, "generic", deformer)
    points = np.array([face.mesh.fp(label) for label in EYE_POINTS])
    camera = frame_points(points, W, H, view=view, margin=0.25)
    with Renderer(face, width=W, height=H, lighting=False, materials=CODED, camera=camera, lashes=False) as r:
        yield face, r


def _disc(face, pose, camera, eye: str, joint: str) -> np.ndarray:
    """Pixels inside the iris's rim (IRISD0 across, on the posed eyeball about its gaze axis)."""
    centre = pose.vertices[face.mesh.joints[joint]]
    front = pose.vertices[pose.parts[eye].start]  # vertex 0 of an eyeball is its front pole (as the renderer)
    radius = np.linalg.norm(front - centre)
    axis = (front - centre) / radius
    e1 = np.cross([0.0, 1.0, 0.0], axis)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    iris = face.fapu.IRISD0 / 2.0
    t = np.linspace(0.0, 2.0 * np.pi, 96, endpoint=False)
    rim = centre + np.sqrt(radius ** 2 - iris ** 2) * axis + iris * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2)
    canvas = Image.new("L", (W, H), 0)
    ImageDraw.Draw(canvas).polygon([tuple(p) for p in camera.project(rim, W, H)[:, :2]], fill=1)
    return np.asarray(canvas, bool)


def measure(face, r, degrees: float) -> list[tuple[float, float]]:
    """Per eye: (upper lid's share of the iris, sclera px per column above the iris) looking ``degrees`` down.

    The share is NaN for an eye seen from the side (its disc under 0.8 of the other's: the far eye at
    three-quarter, whose iris the lid's lateral side hides, 10 % of it looking straight ahead)."""
    value = np.radians(degrees) / ANGLE_UNIT
    pose = face.deform({25: value, 26: value})
    image = r.render(pose).astype(int)
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    iris = (red < 80) & (green > 120)  # iris and pupil
    sclera = (red < 80) & (green < 80) & (blue > 120)
    discs = [_disc(face, pose, r.camera, eye, joint) for eye, joint in EYES]
    biggest = max(d.sum() for d in discs)
    out = []
    for disc in discs:
        rows = np.flatnonzero(disc.any(axis=1))
        upper = disc & (np.arange(H)[:, None] < rows.mean())
        share = float((upper & ~iris).sum() / disc.sum()) if disc.sum() >= 0.8 * biggest else np.nan
        cols = np.flatnonzero(disc.any(axis=0))
        middle = cols[len(cols) // 4: 3 * len(cols) // 4]
        bands = [int(sclera[:np.flatnonzero(iris[:, x]).min(), x].sum()) for x in middle if iris[:, x].any()]
        out.append((share, float(np.mean(bands)) if bands else 0.0))
    return out


def test_the_upper_lid_keeps_its_share_of_the_iris_at_20_degrees(eyes):
    face, r = eyes
    straight = measure(face, r, 0.0)
    for degrees in (-20.0, 20.0):
        for (share, _), (share0, _) in zip(measure(face, r, degrees), straight):
            assert np.isnan(share0) or abs(share - share0) <= SHARE_TOLERANCE, (degrees, share, share0)


def test_no_sclera_above_the_iris_looking_down(eyes):
    """At 10 and 20 deg and on to the full I range: wherever the iris shows, the upper lid sits on it."""
    face, r = eyes
    for degrees in (10.0, 20.0, 30.0, 40.0, FULL_DEG):
        for share, band in measure(face, r, degrees):
            assert band <= SCLERA_ROWS, (degrees, band)

