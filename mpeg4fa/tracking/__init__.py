"""Landmarks and tracking: a face in a photo or video frame -> its landmarks -> the 84 MPEG-4 feature points.

Sits below the encoders and the CLI and above :mod:`mpeg4fa.fdp` and :mod:`mpeg4fa.face`. The
landmark model stays behind :class:`LandmarkFinder` (:mod:`.landmarks`) so it can be swapped; the
landmark -> feature point table is data (``spec/landmark_points.csv``).
"""
from __future__ import annotations

from mpeg4fa.tracking.errors import MissingExtraError, NoFaceError, TrackingError, TrackingWarning
from mpeg4fa.tracking.landmarks import N_LANDMARKS, LandmarkFinder, Landmarks, find_landmarks
from mpeg4fa.tracking.points import SEEN_LABELS, feature_point_array, feature_points
from mpeg4fa.tracking.photo import PhotoFdp, fdp_from_photo, photo_points
from mpeg4fa.tracking.filters import OneEuroFilter
from mpeg4fa.tracking.tracker import FaceTracker, TrackedVideo, fap_stream, track_video

__all__ = [
    "TrackingError", "NoFaceError", "MissingExtraError", "TrackingWarning",
    "N_LANDMARKS", "LandmarkFinder", "Landmarks", "find_landmarks",
    "SEEN_LABELS", "feature_point_array", "feature_points",
    "PhotoFdp", "fdp_from_photo", "photo_points",
    "OneEuroFilter", "FaceTracker", "TrackedVideo", "fap_stream", "track_video",
]
