"""The learned landmark -> FAP map (mpeg4fa.tracking.learned, trained by tools/train_tracker.py): the fit, the
shipped map's bounds and rest, and a real photo moved only rigidly (the real-video path: no face motion read)."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face.fapu import Fapu
from mpeg4fa.tracking import faps as rules
from mpeg4fa.tracking import learned

FAPU = Fapu(IRISD0=20.0, ES0=60.0, ENS0=40.0, MNS0=30.0, MW0=50.0)


def test_fit_recovers_a_linear_map_and_answers_in_the_persons_own_units():
    rng = np.random.default_rng(3)
    moved = rng.normal(0, 0.02, (800, learned.FACE_LANDMARKS, 3))
    angles = rng.normal(0, 0.2, (800, 3))
    landmarks = np.array([13, 14, 61, 291])
    truth = rng.normal(size=(learned.design(moved[:1, landmarks], angles[:1]).shape[1], 2))
    targets = learned.design(moved[:, landmarks], angles) @ truth
    faps = np.array([3, 31])  # MNS and ENS
    values = targets * FAPU.ES0 / np.array([FAPU.unit("MNS"), FAPU.unit("ENS")])
    region = learned.fit_region(moved, angles, values, FAPU, landmarks, faps, ridge=1e-9)
    assert np.allclose(region.predict(moved, angles, FAPU), values, atol=1e-3 * np.abs(values).max())
    wide = Fapu(IRISD0=20.0, ES0=60.0, ENS0=40.0, MNS0=60.0, MW0=50.0)  # a face twice as tall between nose and mouth
    assert np.allclose(region.predict(moved[:5], angles[:5], wide)[:, 0], values[:5, 0] / 2, rtol=1e-3)
    moved[:, 100] += 1.0  # a landmark outside the region moves: nothing read
    assert np.allclose(region.predict(moved[:5], angles[:5], FAPU), values[:5], atol=1e-3 * np.abs(values).max())


def test_shipped_map_is_still_at_rest_and_bounded():
    fap_map = learned.trained_map()
    assert fap_map is not None, "mpeg4fa/tracking/data/fap_map.npz is missing: run tools/train_tracker.py"
    assert all(r.landmarks.max() < learned.FACE_LANDMARKS for r in fap_map.regions)
    assert set(fap_map.faps) <= set(rules.TRANSLATIONS) and len(set(fap_map.faps)) == len(fap_map.faps)
    assert np.all(fap_map.predict(np.zeros((1, learned.FACE_LANDMARKS, 3)), np.zeros((1, 3)), FAPU) == 0)
    wild = np.random.default_rng(4).normal(0, 1.0, (50, learned.FACE_LANDMARKS, 3))  # landmarks thrown an eye distance
    out = fap_map.predict(wild, np.zeros((50, 3)), FAPU)
    assert np.all(np.abs(out) <= fap_map.bound) and fap_map.bound.max() <= 2500  # 1.5 x the widest trained jaw (2.3 MNS0)


def _moved_photo(photo: np.ndarray, shift: tuple[float, float], scale: float, degrees: float) -> np.ndarray:
    """The photo moved in the image plane only (a head that turns, comes closer or slides, its face still)."""
    from skimage.transform import SimilarityTransform, warp

    centre = np.array(photo.shape[1::-1]) / 2.0
    move = (SimilarityTransform(translation=-centre) + SimilarityTransform(scale=scale, rotation=np.radians(degrees))
            + SimilarityTransform(translation=centre + np.array(shift)))
    return (warp(photo, move.inverse, mode="edge") * 255).astype(np.uint8)


@pytest.mark.parametrize("shift, scale, degrees", [((12, -8), 1.0, 0.0), ((0, 0), 0.9, 0.0), ((0, 0), 1.0, 8.0)])
def test_a_real_face_moved_rigidly_reads_as_no_face_motion(astronaut, shift, scale, degrees):
    """The real-video path: the astronaut's photo slid, scaled or rolled reads no more face motion through the map
    than through the rules (:mod:`mpeg4fa.tracking.faps`), and her neutral frame reads 0. Measured, largest |FAP| of
    the map's: slid 63 (rules 68), scaled 42 (106), rolled 8 degrees 90 (76), the last two FAP 19 (53 before the lids
learned from all streams at the penalty 0.0003; 59 at 0.3, where held-out streams read the lids 0.74 for 0.78)."""
    from mpeg4fa.tracking import FaceTracker, LandmarkFinder

    moved = _moved_photo(astronaut, shift, scale, degrees)
    read = {}
    with LandmarkFinder(static=True) as finder:
        for name, fap_map in (("map", "shipped"), ("rules", None)):
            with FaceTracker(25.0, neutral=0, smooth=False, finder=finder, fap_map=fap_map) as tracker:
                for frame in (astronaut, moved):
                    tracker.push(frame)
                read[name] = tracker.values()
    faps = learned.trained_map().faps - 1
    assert np.abs(read["map"][0, faps]).max() < 1e-6  # the neutral frame
    worst_map, worst_rules = np.abs(read["map"][1, faps]).max(), np.abs(read["rules"][1, faps]).max()
    assert worst_map <= 1.25 * worst_rules, (worst_map, worst_rules)
