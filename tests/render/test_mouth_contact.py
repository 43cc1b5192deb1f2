"""The mouth's outline holds its opening (issue 29, item 2): the dark of the mouth never shows past the
lip corners, on every viseme, on the demo stream and on real streams, under both deformers.

Unlit renders with one flat colour per material (as ``test_mouth``): the cavity (red) and the skin's
inside (magenta) are the dark a viewer sees; a pixel of either outside the posed outer lip corners
8.3/8.4 (plus a pixel and a millimetre: the commissure's tip) is a black wedge poking out of the
mouth (the demo's were 3-4 mm).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conftest import face_under
from mpeg4fa.decoded import resolve
from mpeg4fa.fba import decode, demo_stream
from mpeg4fa.render import Materials, Renderer, frame_points
from mpeg4fa.spec.profiles import CHINESE_VISEMES, VISEME_PROFILES

MARKED = Materials().with_colours(skin=(0.5, 0.5, 0.5), lips=(0.5, 0.5, 0.5), teeth=(0, 0, 1), gums=(0, 0, 1),
                                  tongue=(0, 1, 0), cavity=(1, 0, 0), mouth=(1, 0, 1), brows=(1, 1, 0))
SIZE = 160
SLACK_MM = 1.0
REACH_MM = 8.0  # how far beside the corners a wedge is looked for
REAL = Path(__file__).resolve().parents[3] / "shared" / "vectors" / "fba" / "en" / "notification-disclaimer.FBA"
VISEMES = [("mpeg4", name) for name in VISEME_PROFILES["mpeg4"] if name != "none"] + \
          [("zh", v.name) for v in CHINESE_VISEMES]


def dark_outside_corners(r: Renderer, pose) -> int:
    """Pixels of cavity or skin inside beyond the posed outer lip corners (with :data:`SLACK_MM`)."""
    img = r.render(pose).astype(int)
    dark = (np.abs(img - (255, 0, 0)).max(axis=2) < 40) | (np.abs(img - (255, 0, 255)).max(axis=2) < 40)
    idx = [r.face.mesh.fp_index(label) for label in ("8.3", "8.4", "8.1", "8.2")]
    (lx, ly), (rx, ry), (_, top), (_, bottom) = r.camera.project(pose.feature_points[idx], r.width, r.height)[:, :2]
    mm = abs(lx - rx) / max(np.linalg.norm(pose.feature_points[idx[0]] - pose.feature_points[idx[1]]), 1e-9)
    slack = 1.0 + SLACK_MM * mm  # the corner's own pixel, and the commissure's tip beyond the point
    lo, hi = min(lx, rx) - slack, max(lx, rx) + slack
    cols, rows = np.arange(img.shape[1])[None, :], np.arange(img.shape[0])[:, None]
    band = (rows >= top - 2 * slack) & (rows <= bottom + 2 * slack)  # the mouth's height, not the neck below
    reach = REACH_MM * mm  # beside the corners, not the jaw's silhouette further out
    beside = ((cols < lo) & (cols > lo - reach)) | ((cols > hi) & (cols < hi + reach))
    return int((dark & band & beside).sum())


@pytest.fixture(scope="module", params=["fap", "arkit"])
def mouth(request):
    face = face_under(request, "generic", request.param)
    pts = np.array([face.mesh.fp(label) for label in ("8.1", "8.2", "8.3", "8.4", "2.1", "9.15")])
    r = Renderer(face, width=SIZE, height=SIZE, lighting=False, materials=MARKED,
                 camera=frame_points(pts, SIZE, SIZE, margin=0.4))
    yield r
    r.release()


def test_no_dark_past_the_corners_on_any_viseme(mouth):
    bad = {f"{s}/{name}": n for s, name in VISEMES
           if (n := dark_outside_corners(mouth, mouth.face.deform(np.asarray(VISEME_PROFILES[s][name], float))))}
    assert not bad, bad


def test_no_dark_past_the_corners_on_the_demo_stream(mouth):
    """The demo's smile (6/7 stretched) over rounded visemes (53/54 drawn in) once folded both corners."""
    values = resolve(demo_stream())
    bad = {k: n for k in range(0, len(values), 2) if (n := dark_outside_corners(mouth, mouth.face.pose_values(values[k])))}
    assert not bad, bad


def test_no_dark_past_the_corners_on_a_real_stream(mouth):
    if not REAL.is_file():
        pytest.skip(f"real stream not present ({REAL})")
    values = resolve(decode(REAL.read_bytes()))
    bad = {k: n for k in range(0, len(values), 3) if (n := dark_outside_corners(mouth, mouth.face.pose_values(values[k])))}
    assert not bad, bad


def test_the_check_sees_a_folded_corner(mouth):
    """Without the outline rule (inner corner 3 mm past the outer one) the wedge is there to see."""
    face = mouth.face
    rig = face.rig
    v = np.zeros(68)
    v[5] = v[6] = 150  # stretch the inner corners (MW)
    v[52] = v[53] = -100  # draw the outer corners in
    pose = face.deform(v)
    assert dark_outside_corners(mouth, pose) == 0
    from mpeg4fa.face.deformers.feature_points import pose_in_head_frame
    saved = rig.corners
    object.__setattr__(rig, "corners", ())
    try:
        folded = face.deform(v) if face.deformer == "fap" else None
    finally:
        object.__setattr__(rig, "corners", saved)
    if folded is not None:
        assert dark_outside_corners(mouth, folded) > 0
    assert pose_in_head_frame  # the rule lives in the layer every deformer shares


def _marked(mouth, pose) -> dict[str, np.ndarray]:
    img = mouth.render(pose).astype(int)
    return {name: np.abs(img - c).max(axis=2) < 40 for name, c in
            (("teeth", (0, 0, 255)), ("tongue", (0, 255, 0)), ("cavity", (255, 0, 0)), ("back", (255, 0, 255)))}


def _px(mouth, pose, labels) -> np.ndarray:
    idx = [mouth.face.mesh.fp_index(label) for label in labels]
    return mouth.camera.project(pose.feature_points[idx], mouth.width, mouth.height)[:, :2]


@pytest.mark.parametrize("set_name,name", [("mpeg4", "PP"), ("zh", "bpm")])
def test_bilabials_seal_the_lips_at_every_column(mouth, set_name, name):
    """PP/B/M: nothing of the mouth's inside shows between the inner corners, at any column."""
    pose = mouth.face.deform(np.asarray(VISEME_PROFILES[set_name][name], float))
    masks = _marked(mouth, pose)
    (lx, _), (rx, _) = _px(mouth, pose, ("2.4", "2.5"))
    inside = masks["teeth"] | masks["tongue"] | masks["cavity"] | masks["back"]
    cols = inside[:, int(np.ceil(min(lx, rx))):int(max(lx, rx)) + 1].any(axis=0)
    assert not cols.any(), f"{cols.sum()} of {len(cols)} columns show the inside: {np.flatnonzero(cols)}"


def test_ff_lower_lip_under_the_upper_incisors(mouth):
    """FF: the lower lip's inner edge (2.3) touches the upper incisors' biting edge (9.10) from in front
    and below, and the incisors show above it."""
    face = mouth.face
    pose = face.deform(np.asarray(VISEME_PROFILES["mpeg4"]["FF"], float))
    fp = dict(zip(face.mesh.fp_labels, pose.feature_points))
    lip, edge = fp["2.3"], fp["9.10"]
    assert np.linalg.norm(lip - edge) <= 1.8, (lip, edge)
    assert lip[2] >= edge[2] and lip[1] <= edge[1] + 1.5, "the lip is under the teeth's edge, not behind or above it"
    masks = _marked(mouth, pose)
    (cx, top), (_, bottom) = _px(mouth, pose, ("2.2", "2.3"))
    band = masks["teeth"][int(top) - 2:int(bottom) + 3, int(cx) - 3:int(cx) + 4]
    mm = abs(_px(mouth, pose, ("8.3",))[0, 0] - _px(mouth, pose, ("8.4",))[0, 0]) / abs(fp["8.3"][0] - fp["8.4"][0])
    assert band.sum(axis=0).min() >= 1.5 * mm, "upper incisors visible above the lower lip"


def test_th_tongue_between_the_teeth_seen_from_the_front(mouth):
    face = mouth.face
    pose = face.deform(np.asarray(VISEME_PROFILES["mpeg4"]["TH"], float))
    fp = dict(zip(face.mesh.fp_labels, pose.feature_points))
    tip = fp["6.1"]
    assert fp["9.11"][1] < tip[1] < fp["9.10"][1], "the tip between the lower and upper biting edges"
    assert tip[2] >= fp["9.10"][2] + 2.0, "and out past the upper incisors"
    assert _marked(mouth, pose)["tongue"].sum() >= 40, "the tongue shows from the front"


@pytest.mark.parametrize("name", ["DD", "nn"])
def test_t_d_l_tongue_tip_up_at_the_ridge(mouth, name):
    """T/D and L: the tongue tip raised above the upper biting edge, behind the upper teeth (the ridge)."""
    face = mouth.face
    fp = dict(zip(face.mesh.fp_labels, face.deform(np.asarray(VISEME_PROFILES["mpeg4"][name], float)).feature_points))
    tip, edge = fp["6.1"], fp["9.10"]
    assert tip[1] >= edge[1] + 3.0, f"tip {tip[1] - edge[1]:.1f} mm above the upper biting edge"
    assert edge[2] - 9.0 <= tip[2] <= edge[2] - 3.0, f"tip {edge[2] - tip[2]:.1f} mm behind the incisors' edge"


@pytest.mark.parametrize("name", ["AA", "oh"])
def test_teeth_at_three_quarter_without_stripes(mouth, name):
    """Seen from the side the molars' bulge and gap shading read as stripes (15 % of the visible teeth
    pixels 12 grey levels off their row's 9-pixel mean, 9 % with the front teeth's gaps alone)."""
    from scipy.ndimage import binary_erosion, uniform_filter1d

    face = mouth.face
    pose = face.deform(np.asarray(VISEME_PROFILES["mpeg4"][name], float))
    pts = np.array([face.mesh.fp(label) for label in ("8.1", "8.2", "8.3", "8.4", "2.1")])
    camera = frame_points(pts, 300, 300, margin=0.3, view="three-quarter")
    with Renderer(face, width=300, height=300, camera=camera, samples=4) as lit, \
            Renderer(face, width=300, height=300, camera=camera, lighting=False, materials=MARKED) as flat:
        grey = lit.render(pose).astype(float).mean(axis=2)
        teeth = binary_erosion(np.abs(flat.render(pose).astype(int) - (0, 0, 255)).max(axis=2) < 40, iterations=2)
    ripple = np.abs(grey - uniform_filter1d(grey, 9, axis=1))[teeth]
    assert teeth.sum() > 500
    assert (ripple > 12).mean() <= 0.12
