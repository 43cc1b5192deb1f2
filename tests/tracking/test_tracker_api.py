"""FaceTracker frame by frame: rows from the first push with a given neutral, lost frames held and counted,
the default neutral chosen after the first seconds with every frame still getting its row."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.tracking import FaceTracker, NoFaceError, TrackingError


def _moved(landmarks: np.ndarray, drop: float) -> np.ndarray:
    """The landmarks with the chin (152) and lower lip (14, 17) lowered by ``drop`` pixels."""
    moved = landmarks.copy()
    moved[[152, 14, 17], 1] += drop
    return moved


def test_rows_come_from_the_first_push_and_lost_frames_hold(astronaut_landmarks):
    points = astronaut_landmarks.points
    tracker = FaceTracker(25, neutral=0, smooth=False)
    first = tracker.push_landmarks(points)
    assert first.shape == (68,) and first.dtype == np.int32 and np.abs(first).max() == 0
    opened = tracker.push_landmarks(_moved(points, 6.0))
    assert opened[2] > 100                       # FAP 3 open_jaw
    held = tracker.push_landmarks(None)
    assert np.array_equal(held, opened) and tracker.lost == 1
    summary = tracker.finish()
    assert summary.frames == 3 and summary.lost == 1 and summary.neutral.how == "given"
    stream = tracker.stream()
    assert len(stream) == 3 and stream.fap_values[1, 2] == opened[2]


def test_default_neutral_waits_for_the_first_seconds_then_answers_every_frame(astronaut_landmarks):
    points = astronaut_landmarks.points
    tracker = FaceTracker(10)                    # 3 s = 30 frames of search
    answers = [tracker.push_landmarks(_moved(points, 8.0 if 5 <= k < 9 else 0.0)) for k in range(35)]
    assert all(a is None for a in answers[:29]) and all(a is not None for a in answers[29:])
    values = tracker.values()
    assert values.shape == (35, 68) and tracker.finish().neutral.first not in range(5, 9)
    assert values[6, 2] > 100 > abs(values[20, 2])


def test_no_face_at_all_and_bad_arguments_are_errors():
    tracker = FaceTracker(25, where="empty.mp4")
    for _ in range(3):
        assert tracker.push_landmarks(None) is None
    with pytest.raises(NoFaceError, match="empty.mp4: no face found in any of the 3 frames"):
        tracker.finish()
    with pytest.raises(TrackingError):
        FaceTracker(0)
    with pytest.raises(TrackingError):
        FaceTracker(25, neutral=-1)
