"""A face's landmarks -> the MPEG-4 feature points it shows, through ``spec/landmark_points.csv``."""
from __future__ import annotations

import numpy as np

from mpeg4fa.spec.landmark_points import LANDMARK_POINTS
from mpeg4fa.tracking.landmarks import Landmarks

__all__ = ["SEEN_LABELS", "feature_points", "feature_point_array"]

SEEN_LABELS: tuple[str, ...] = tuple(LANDMARK_POINTS)
"""The feature points a photo shows (59 of 84), in label order; the rest come from the calibrated head."""
_MIX = np.zeros((len(SEEN_LABELS), 478))
for _row, _label in enumerate(SEEN_LABELS):
    _MIX[_row, list(LANDMARK_POINTS[_label].indices)] = LANDMARK_POINTS[_label].weights
_MIX.flags.writeable = False


def feature_point_array(points: np.ndarray) -> np.ndarray:
    """(len(SEEN_LABELS), 3) feature points from a (478, 3) landmark array (or (N, 478, 3) frames at once)."""
    return np.einsum("fl,...lc->...fc", _MIX, np.asarray(points, dtype=np.float64))


def feature_points(landmarks: Landmarks) -> dict[str, np.ndarray]:
    """``{label: (x, y, z)}`` of every seen feature point, in the landmarks' pixels (x right, y down, z
    toward the camera negative)."""
    return dict(zip(SEEN_LABELS, feature_point_array(landmarks.points)))
