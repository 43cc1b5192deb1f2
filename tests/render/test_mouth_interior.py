"""The inside of the mouth at three-quarter (issue 29 item 2; generic head, every exact deformer).

Drawn unlit with colour-coded materials (skin and lips red, the skin's back faces green, cavity black,
teeth, gums and tongue blue), the mouth's interior is the black and blue pixels:

* it shows only inside the lips' outline (the outer lip contour 8.x as the lip colour's spline,
  :data:`~mpeg4fa.render.materials.LIP_OUTLINE`, projected from the pose, 3 px grown), on every viseme,
  MPEG-4 and Chinese, front and three-quarter;
* the grey shapes seen through the open lips at three-quarter on TH, AA, E and oh were the far side's
  premolars and molars, their outer faces turned toward the camera by the arch and lit by the key light
  (which sits on that side) at 0.3 of a front tooth: a flat grey wall against the dark cavity. Lit, the
  teeth pixels where the far back teeth project now read as in the mouth's shadow;
* lit evenly, the tongue read as a flat pink slab there, cut by a hard dark notch where the far lower molars
  stand in front of its edge: it now lies in the mouth's shadow too, lit at its tip and darker back along it
  and toward its edges (:func:`~mpeg4fa.render.details.tongue_coordinates`).
"""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image, ImageDraw
from scipy import ndimage
from scipy.interpolate import CubicSpline

from conftest import EXACT_DEFORMERS, face_under
from mpeg4fa.render import Materials, Renderer, frame_points
from mpeg4fa.render.details import tooth_coordinates
from mpeg4fa.render.materials import LIP_OUTLINE
from mpeg4fa.spec import VISEMES
from mpeg4fa.spec.profiles import CHINESE_VISEMES, VISEME_PROFILES

pytestmark = pytest.mark.usefixtures("generic_head_installed")

SIZE = 384
MOUTH_POINTS = ("2.1", "8.1", "8.3", "8.4", "9.15", "2.10")
CODED = Materials().with_colours(skin=(1, 0, 0), lips=(1, 0, 0), mouth=(0, 1, 0), cavity=(0, 0, 0),
                                 teeth=(0, 0, 1), gums=(0, 0, 1), tongue=(0, 0, 1), background=(1, 1, 0))
LOOKS = ([(f"mpeg4 {v.name}", VISEME_PROFILES["mpeg4"][v.name]) for v in VISEMES if v.number]
         + [(f"zh {v.name}", VISEME_PROFILES["zh"][v.name]) for v in CHINESE_VISEMES])
GREY_VISEMES = ("TH", "AA", "E", "oh")
FAR_BACK_LUMA = 12.0
"""Mean lit luma (0-255) allowed for the teeth pixels where the far premolars and molars are nearest, at
three-quarter: measured 58-63 on TH, AA, E and oh before (the grey wall against the cavity's 10-20),
26-28 in their shadow at 0.12 of a front tooth (still a grey slab with a jagged top at 512 px), 14-15 at 0.06,
7.8-8.4 at 0.03 (a faint shape in the dark); the incisors in front stay bright (tests/render/test_mouth.py)."""
SHADOWED_TONGUE = ("AA", "oh", "E")  # the visemes whose tongue shows beside the far back teeth at three-quarter
TONGUE_SPREAD = 0.45
"""The tongue's 10th-percentile lit luma at most this share of its 90th at three-quarter: measured 0.73, 0.78 and
0.82 on AA, oh and E lit evenly (a flat slab), 0.28, 0.29 and 0.32 in the mouth's shadow."""
TONGUE_TIP_LUMA = 60.0
"""...while its lit front keeps a 90th-percentile luma of at least this: measured 99, 88 and 70 (102, 95, 84 before)."""
NOTCH_STEP = 50.0
"""Largest mean luma step from the tongue to the far back teeth where they meet (pixels within 3 px of the other):
measured 80, 74 and 68 lit evenly (the notch), 39, 38 and 33 in the mouth's shadow."""


@pytest.fixture(scope="module", params=[(view, d) for d in EXACT_DEFORMERS for view in ("front", "three-quarter")],
                ids=lambda p: f"{p[1]}-{p[0]}")
def mouth(request):
    view, deformer = request.param
    face = face_under(request, "generic", deformer)
    camera = frame_points(np.array([face.mesh.fp(label) for label in MOUTH_POINTS]), SIZE, SIZE, view=view)
    with Renderer(face, width=SIZE, height=SIZE, camera=camera, lighting=False, materials=CODED) as r:
        yield face, r, view


def _pose(face, values):
    v = np.asarray(values, float).copy()
    v[:2] = 0
    return face.pose_values(v)


def _outline(face, pose, camera) -> np.ndarray:
    """Pixels inside the outer lip contour (the periodic spline through 8.x, as the lip colour's), 3 px grown
    (the spline rounds the sharp lip corners by up to 2 px: a rounded mouth's opening reaches them)."""
    ring = pose.feature_points[[face.mesh.fp_index(label) for label in LIP_OUTLINE]]
    loop = np.vstack([ring, ring[:1]])
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(loop, axis=0), axis=1))]
    curve = CubicSpline(chord, loop, bc_type="periodic")(np.linspace(0.0, chord[-1], 161))
    canvas = Image.new("L", (SIZE, SIZE), 0)
    ImageDraw.Draw(canvas).polygon([tuple(p) for p in camera.project(curve, SIZE, SIZE)[:, :2]], fill=1)
    return ndimage.binary_dilation(np.asarray(canvas, bool), iterations=3)


def _interior(image: np.ndarray) -> np.ndarray:
    """Cavity, teeth, gums and tongue (the skin's back faces, green, peek through at grazing silhouettes
    as single pixels anywhere: not the mouth's)."""
    r, g = image[..., 0].astype(int), image[..., 1].astype(int)
    return (r < 100) & (g < 100)


def test_the_mouth_s_inside_shows_only_within_the_lips(mouth):
    face, r, view = mouth
    opened = 0
    for name, values in LOOKS:
        pose = _pose(face, values)
        inside = _interior(r.render(pose))
        opened += bool(inside.any())
        outside = inside & ~_outline(face, pose, r.camera)
        assert outside.sum() == 0, (view, name, int(outside.sum()))
    assert opened >= 20  # the test sees open mouths: 27 of the 29 looks show their inside


def _far_back_teeth(face, pose, camera) -> np.ndarray:
    """Pixels where the nearest tooth is one of the far side's premolars and molars (tooth coordinate 3.5
    and more along the arch): both arches' triangles rasterised with a depth test."""
    mesh = face.mesh
    far_side = -np.sign(camera.position[0] - mesh.fp("2.2")[0])  # the face's side away from the camera
    depth = np.full((SIZE, SIZE), np.inf)
    back = np.zeros((SIZE, SIZE), bool)
    ys, xs = np.mgrid[0:SIZE, 0:SIZE] + 0.5
    for part, upper in (("teeth_upper", True), ("teeth_lower", False)):
        s = mesh.part(part)
        far = far_side * tooth_coordinates(mesh.vertices[s], upper)[:, 0] >= 3.5
        tri = np.asarray(mesh.triangles[part])
        tri = tri - s.start if tri.min() >= s.start else tri
        p = camera.project(pose.vertices[s], SIZE, SIZE)
        for t in tri:
            (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = p[t]
            area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
            if abs(area) < 1e-9:
                continue
            c0, c1 = int(max(min(x0, x1, x2), 0)), int(min(max(x0, x1, x2) + 1, SIZE))
            r0, r1 = int(max(min(y0, y1, y2), 0)), int(min(max(y0, y1, y2) + 1, SIZE))
            if c0 >= c1 or r0 >= r1:
                continue
            px, py = xs[r0:r1, c0:c1], ys[r0:r1, c0:c1]
            w1 = ((px - x0) * (y2 - y0) - (x2 - x0) * (py - y0)) / area
            w2 = ((x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)) / area
            w0 = 1.0 - w1 - w2
            z = w0 * z0 + w1 * z1 + w2 * z2
            hit = (w0 >= 0) & (w1 >= 0) & (w2 >= 0) & (z < depth[r0:r1, c0:c1])
            depth[r0:r1, c0:c1][hit] = z[hit]
            back[r0:r1, c0:c1][hit] = bool(far[t].all())
    return back


def _three_quarter(request, name):
    """The lit luma of viseme ``name`` at three-quarter, and its teeth, far back teeth and tongue pixels (unlit,
    colour-coded: teeth and gums blue, tongue green)."""
    face = face_under(request, "generic", "fap")
    camera = frame_points(np.array([face.mesh.fp(label) for label in MOUTH_POINTS]), SIZE, SIZE, view="three-quarter")
    pose = _pose(face, VISEME_PROFILES["mpeg4"][name])
    with Renderer(face, width=SIZE, height=SIZE, camera=camera, lighting=False,
                  materials=Materials().with_colours(teeth=(0, 0, 1), gums=(0, 0, 1), tongue=(0, 1, 0))) as flat, \
            Renderer(face, width=SIZE, height=SIZE, camera=camera) as lit:
        coded = flat.render(pose).astype(int)
        luma = lit.render(pose).astype(float) @ np.array([0.2126, 0.7152, 0.0722])
    r, g, b = coded[..., 0], coded[..., 1], coded[..., 2]
    teeth = (b > 200) & (r < 50) & (g < 50)
    tongue = (g > 200) & (r < 50) & (b < 50)
    return luma, teeth, teeth & _far_back_teeth(face, pose, camera), tongue


@pytest.mark.parametrize("name", GREY_VISEMES)
def test_far_back_teeth_sit_in_the_mouth_s_shadow(request, name):
    luma, _teeth, far, _tongue = _three_quarter(request, name)
    assert far.sum() >= 100, (name, int(far.sum()))  # they show (measured 300-1000 px)
    assert luma[far].mean() <= FAR_BACK_LUMA, (name, float(luma[far].mean()))


@pytest.mark.parametrize("name", SHADOWED_TONGUE)
def test_the_tongue_lies_in_the_mouth_s_shadow(request, name):
    """Lit at its tip, darker back along it and toward its edges; where the far lower molars stand in front of its
    edge, the two meet without a hard notch."""
    luma, _teeth, far, tongue = _three_quarter(request, name)
    assert tongue.sum() >= 300, (name, int(tongue.sum()))  # it shows (measured 617-2888 px)
    low, high = np.percentile(luma[tongue], [10, 90])
    assert high >= TONGUE_TIP_LUMA and low <= TONGUE_SPREAD * high, (name, float(low), float(high))
    near_far = tongue & ndimage.binary_dilation(far, iterations=3)
    near_tongue = far & ndimage.binary_dilation(tongue, iterations=3)
    assert near_far.sum() >= 30, (name, int(near_far.sum()))  # they meet (measured 57-132 px)
    step = luma[near_far].mean() - luma[near_tongue].mean()
    assert step <= NOTCH_STEP, (name, float(step))
