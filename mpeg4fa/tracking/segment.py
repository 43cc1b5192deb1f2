"""Which pixels of a photo are the person: MediaPipe's selfie segmentation (in the same wheel as Face Mesh).

Used before a photo goes out as a face's texture: a receiver maps its own head onto the photo, and
where that head is wider than the person's face (the jaw, the ears, the sides of the hair) it would
pick up the background. :func:`extend_person` paints the background with the nearest person
pixels instead, so those parts wear skin and hair colours, not the wall behind.
"""
from __future__ import annotations

import warnings

import numpy as np
from scipy import ndimage

from mpeg4fa.tracking.landmarks import OPENING_RINGS, _quiet_native_stderr, check_rgb
from mpeg4fa.tracking.errors import MissingExtraError

__all__ = ["person_mask", "extend_person", "close_openings"]

MIN_PERSON = 0.01
"""Smallest share of the photo the person may cover; below it the mask is not trusted."""


def person_mask(rgb: np.ndarray, where: str | None = None) -> np.ndarray:
    """(H, W) bool: the pixels that show a person (face, hair, body), not the background."""
    image = check_rgb(rgb, where)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from mediapipe.python.solutions import selfie_segmentation
    except ImportError as exc:
        raise MissingExtraError(f"the segmentation model (mediapipe) is not installed ({exc})") from None
    with _quiet_native_stderr():
        with selfie_segmentation.SelfieSegmentation(model_selection=0) as model:
            result = model.process(image)
    mask = result.segmentation_mask
    if mask is None or mask.shape != image.shape[:2]:   # pragma: no cover - the model always answers
        return np.ones(image.shape[:2], bool)
    return np.asarray(mask) > 0.5


def extend_person(rgb: np.ndarray, mask: np.ndarray, *, inset: int = 2) -> np.ndarray:
    """A copy of ``rgb`` whose background pixels take the colour of the nearest person pixel.

    ``inset`` pixels of the person's edge count as background too (the mask's edge mixes both).
    Returns ``rgb`` unchanged when the person covers less than :data:`MIN_PERSON` of it.
    """
    person = ndimage.binary_erosion(mask, iterations=inset) if inset > 0 else mask
    if person.mean() < MIN_PERSON:
        return rgb
    _, (rows, cols) = ndimage.distance_transform_edt(~person, return_indices=True)
    return rgb[rows, cols]


def close_openings(rgb: np.ndarray, landmarks: np.ndarray) -> np.ndarray:
    """The photo with its eye openings and open mouth painted over from the skin around them.

    A photo sent as a face's texture is worn by a head with eyes, teeth and a mouth of its own: left
    in, the photo's eyes would show on closed lids and a smile's teeth on closed lips (a band like
    braces). ``landmarks``: the (478, 3) or (478, 2) pixels of :class:`~.landmarks.Landmarks`.
    """
    import cv2

    image = np.ascontiguousarray(check_rgb(rgb))
    mask = np.zeros(image.shape[:2], np.uint8)
    for ring in OPENING_RINGS.values():
        cv2.fillPoly(mask, [np.rint(np.asarray(landmarks)[list(ring), :2]).astype(np.int32)], 255)
    mask = cv2.dilate(mask, np.ones((5, 5), np.uint8))
    return cv2.inpaint(image, mask, 7, cv2.INPAINT_TELEA)
