"""The landmark interface and the landmark -> feature point table on a real photo (scikit-image's astronaut)."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.errors import MpegFaError
from mpeg4fa.spec import FEATURE_POINT_MIRROR, FEATURE_POINTS
from mpeg4fa.spec.landmark_points import LANDMARK_POINTS, LANDMARK_SOURCES
from mpeg4fa.tracking import (N_LANDMARKS, LandmarkFinder, NoFaceError, SEEN_LABELS, TrackingError,
                              TrackingWarning, feature_point_array, feature_points, find_landmarks)

_SIDE = {fp.label: fp.side for fp in FEATURE_POINTS}


def test_table_covers_every_feature_point_and_says_why():
    assert [s.label for s in LANDMARK_SOURCES] == [fp.label for fp in FEATURE_POINTS]
    assert all(s.notes for s in LANDMARK_SOURCES)
    unseen = {s.label for s in LANDMARK_SOURCES if not s.seen}
    # what a front photo cannot show: tongue, spine, teeth, ears (but their contact with the face), skull
    assert {"6.1", "6.2", "6.3", "6.4", "7.1", "9.8", "9.9", "9.10", "9.11", "10.1", "10.3", "11.4", "11.6"} <= unseen
    assert all(abs(sum(s.weights) - 1.0) < 1e-12 for s in LANDMARK_POINTS.values())


def test_twins_use_mirrored_landmarks(astronaut_landmarks):
    """A point and its mirror twin are seen both or neither (the face is symmetric)."""
    for label, twin in FEATURE_POINT_MIRROR.items():
        assert (label in LANDMARK_POINTS) == (twin in LANDMARK_POINTS), label


def test_astronaut_478_landmarks_in_pixels(astronaut, astronaut_landmarks):
    lm = astronaut_landmarks
    assert lm.points.shape == (N_LANDMARKS, 3) and lm.faces == 1 and lm.size == (512, 512)
    x0, y0, x1, y1 = lm.box
    # the face lies in the photo's upper middle (measured by eye: about x 180-270, y 70-180)
    assert 150 < x0 < 200 and 250 < x1 < 300 and 50 < y0 < 100 and 160 < y1 < 200
    # depth is in the same pixel scale: the head is ~ as deep as wide, not 1/512 of it
    assert 20 < np.ptp(lm.points[:, 2]) < 1.5 * (x1 - x0)


def test_feature_points_inside_the_face_and_sided(astronaut_landmarks):
    lm = astronaut_landmarks
    fp = feature_points(lm)
    assert list(fp) == list(SEEN_LABELS) and len(fp) == 59
    x0, y0, x1, y1 = lm.box
    for label, (x, y, _) in fp.items():
        assert x0 - 1 <= x <= x1 + 1 and y0 - 1 <= y <= y1 + 1, label
    # the face's own left is the image's right in a front photo
    for label, twin in FEATURE_POINT_MIRROR.items():
        if _SIDE[label] == "left" and label in fp:
            assert fp[label][0] > fp[twin][0], (label, twin)
    assert fp["8.3"][0] > fp["8.4"][0] and fp["3.5"][0] > fp["3.6"][0]
    mid_x = (fp["3.7"][0] + fp["3.12"][0]) / 2
    assert fp["8.3"][0] > mid_x > fp["8.4"][0]
    # eyes above the nose tip above the mouth above the chin (y down)
    assert fp["3.5"][1] < fp["9.3"][1] < fp["8.1"][1] < fp["8.2"][1] < fp["2.1"][1]
    assert fp["9.3"][2] < fp["3.5"][2]          # the nose tip is nearer the camera than the eyes


def test_eye_centres_at_the_irises(astronaut, astronaut_landmarks):
    """3.5 / 3.6 lie on the dark iris, between the eye corners and between the lids."""
    fp = feature_points(astronaut_landmarks)
    grey = astronaut.mean(axis=2)
    skin = np.median(grey[int(fp["9.3"][1]) - 3:int(fp["9.3"][1]) + 3, int(fp["9.3"][0]) - 12:int(fp["9.3"][0]) - 6])
    for eye, outer, inner, up, down in (("3.5", "3.7", "3.11", "3.1", "3.3"), ("3.6", "3.12", "3.8", "3.2", "3.4")):
        x, y, _ = fp[eye]
        assert min(fp[outer][0], fp[inner][0]) < x < max(fp[outer][0], fp[inner][0])
        assert fp[up][1] < y < fp[down][1]
        iris = grey[int(round(y)) - 1:int(round(y)) + 2, int(round(x)) - 1:int(round(x)) + 2].mean()
        assert iris < 0.6 * skin, eye


def test_mapping_runs_on_many_frames_at_once(astronaut_landmarks):
    one = feature_point_array(astronaut_landmarks.points)
    many = feature_point_array(np.stack([astronaut_landmarks.points] * 3))
    assert many.shape == (3, 59, 3) and np.allclose(many[1], one)


def test_no_face_is_one_located_error():
    from skimage import data
    with pytest.raises(NoFaceError, match="coffee.png: no face found"):
        find_landmarks(data.coffee(), "coffee.png")


def test_bad_arrays_are_refused():
    with pytest.raises(TrackingError, match="uint8"):
        find_landmarks(np.zeros((64, 64, 3), np.float32), "x")
    with pytest.raises(NoFaceError, match="too small"):
        find_landmarks(np.zeros((8, 64, 3), np.uint8), "tiny.png")
    assert issubclass(TrackingError, MpegFaError)


def test_two_faces_take_the_largest_and_warn_once(astronaut):
    from PIL import Image
    face = astronaut[20:260, 110:340]
    small = np.asarray(Image.fromarray(face).resize((face.shape[1] * 2 // 3, face.shape[0] * 2 // 3)))
    canvas = np.full((300, 420, 3), 200, np.uint8)
    canvas[30:30 + face.shape[0], 10:10 + face.shape[1]] = face
    canvas[40:40 + small.shape[0], 250:250 + small.shape[1]] = small
    with LandmarkFinder(static=True) as finder:
        with pytest.warns(TrackingWarning, match="two.png: 2 faces found; the largest is used"):
            found = finder.find(canvas, "two.png")
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("error", TrackingWarning)
            again = finder.find(canvas, "two.png")          # said once per finder
    assert found.faces == 2 and again.faces == 2
    assert found.box[2] < 250                              # the big face, on the left
