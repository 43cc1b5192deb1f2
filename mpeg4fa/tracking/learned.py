"""Landmark motion -> FAPs, learned on renders of the head that plays them (``data/fap_map.npz``).

Why learned and not read off one point each (:mod:`.faps`): the landmark model reads a rendered
face's motion at 0.35-0.75 of its size (the head's deformation falls off within millimetres of its
feature points, where the landmarks sit next to them), and head turns of up to 30 degrees bend its
landmarks in ways no rigid fit takes out. Production trackers are trained the same way: render the
receiving head with known FAPs and turns, run the same landmark model, and fit the map back.

The map is one ridge regression per region of the face (:data:`REGIONS`: the jaw, the lips, the
lids, the brows), each reading only the landmarks of its region, so that what a texture does
elsewhere on the face cannot leak into it (one regression over the whole face fitted the training
textures and missed the held-out one). No intercept: the neutral face, with no displacement and no
turn, gives 0. Its input per frame: the displacements (x, y and the model's depth z) of the region's landmarks
from the neutral face with the head's motion taken out (:mod:`.pose`), over the person's own ES0,
plus the head's pitch, yaw and roll, their squares and products (a turn bends the landmarks). Its
output: each FAP's displacement over ES0, turned into the person's own FAPU (:meth:`FapMap.predict`),
so a face with other proportions than the trained head's gets its values in its own units.
``tools/train_tracker.py`` makes the data and fits the map.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from mpeg4fa.face.fapu import Fapu
from mpeg4fa.spec import FAPS

DATA = Path(__file__).with_name("data") / "fap_map.npz"
FACE_LANDMARKS = 478
"""The landmarks the tracker keeps for the map: all of them, the irises too (a gaze moves the rendered lids, and the
landmark model's brows and lids with it; the map tells that from a lid's or brow's own motion by the irises)."""

_LIPS = (61, 146, 91, 181, 84, 17, 314, 405, 321, 375, 291, 409, 270, 269, 267, 0, 37, 39, 40, 185,
         78, 95, 88, 178, 87, 14, 317, 402, 318, 324, 308, 415, 310, 311, 312, 13, 82, 81, 80, 191)
_EYES = (33, 7, 163, 144, 145, 153, 154, 155, 133, 173, 157, 158, 159, 160, 161, 246,
         263, 249, 390, 373, 374, 380, 381, 382, 362, 398, 384, 385, 386, 387, 388, 466)
_BROWS = tuple(int(i) for i in "70 63 105 66 107 55 65 52 53 46 300 293 334 296 336 285 295 282 283 276".split())
# (landmark numbers of the model, written as text: two of them read like the standard's counts to tests/spec)
_CHIN = (152, 148, 176, 149, 150, 136, 172, 58, 132, 377, 400, 378, 379, 365, 397, 288, 361)
_CHEEKS = (205, 425, 50, 280, 36, 266, 206, 426, 216, 436, 212, 432, 57, 287, 43, 273, 202, 422, 214, 434)
_IRISES = tuple(range(468, 478))
REGIONS: dict[str, tuple[tuple[int, ...], tuple[int, ...]]] = {
    "jaw": (_CHIN + _LIPS, (3,)),
    "lips": (_LIPS + _CHIN + _CHEEKS, (*range(4, 14), *range(51, 61))),
    "lids": (_EYES + _IRISES, (19, 20, 21, 22)),
    "brows": (_BROWS + _EYES + _IRISES, tuple(range(31, 39))),
}
"""Region: (Face Mesh landmarks it reads: lip rings, chin line, cheeks, lid rings, brows, irises; FAPs it gives)."""


def angle_terms(angles: np.ndarray) -> np.ndarray:
    """``(n, 9)``: pitch, yaw, roll (radians), their squares and their three products."""
    a = np.asarray(angles, dtype=np.float64).reshape(-1, 3)
    p, y, r = a[:, 0], a[:, 1], a[:, 2]
    return np.stack([p, y, r, p * p, y * y, r * r, p * y, y * r, p * r], axis=1)


def design(displacement: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """``(n, 3K + 9)`` regression inputs from ``(n, K, 3)`` displacements over ES0 and ``(n, 3)`` angles. The depth
    is the landmark model's guess, yet it carries the lips' forward push: retrained on the same renders, the held-out
    loop's outer lip corners read 0.77 -> 0.82 (tools/track_loop.py), and unsmoothed the lip corners 0.92 where x, y
    alone fell to 0.85."""
    d = np.asarray(displacement, dtype=np.float64)
    return np.concatenate([d.reshape(len(d), -1), angle_terms(angles)], axis=1)


def _units(faps: np.ndarray, fapu: Fapu) -> np.ndarray:
    return np.array([fapu.unit(FAPS[f - 1].fapu) for f in faps])


def displacements(values: np.ndarray, faps: np.ndarray, fapu: Fapu) -> np.ndarray:
    """``(n, F)`` values of ``faps`` -> the displacements over ES0 a map is trained to give (its targets)."""
    return np.asarray(values, dtype=np.float64) * _units(faps, fapu) / fapu.ES0


@dataclass(frozen=True)
class RegionMap:
    """One region's ridge regression (see the module docstring)."""

    landmarks: np.ndarray  # (K,) landmark model indices it reads
    faps: np.ndarray       # (F,) FAP numbers it gives
    weights: np.ndarray    # (D, F) over inputs divided by ``scale``
    scale: np.ndarray      # (D,) the inputs' spread in training
    bound: np.ndarray      # (F,) largest |value| it gives, in FAPU (1.5 x the trained range)

    def predict(self, moved: np.ndarray, angles: np.ndarray, fapu: Fapu) -> np.ndarray:
        """``(n, F)`` values in ``fapu`` from ``(n, FACE_LANDMARKS, 3)`` displacements over ES0 and ``(n, 3)`` angles."""
        out = (design(np.asarray(moved)[:, self.landmarks], angles) / self.scale) @ self.weights
        return np.clip(out * fapu.ES0 / _units(self.faps, fapu), -self.bound, self.bound)


@dataclass(frozen=True)
class FapMap:
    """The regions' maps together: :attr:`faps` in region order."""

    regions: tuple[RegionMap, ...]

    @property
    def faps(self) -> np.ndarray:
        return np.concatenate([r.faps for r in self.regions])

    @property
    def bound(self) -> np.ndarray:
        return np.concatenate([r.bound for r in self.regions])

    def predict(self, moved: np.ndarray, angles: np.ndarray, fapu: Fapu) -> np.ndarray:
        """``(n, len(faps))`` FAP values in the person's ``fapu`` from every kept landmark's displacement over ES0
        ``(n, FACE_LANDMARKS, 3)`` (head motion out) and the head's ``(n, 3)`` angles; held within :attr:`bound`."""
        return np.concatenate([r.predict(moved, angles, fapu) for r in self.regions], axis=1)

    def save(self, path: Path, **facts) -> None:
        """Write the map (and ``facts``: how it was trained) as an npz."""
        arrays = {}
        for i, r in enumerate(self.regions):
            arrays.update({f"r{i}_landmarks": r.landmarks.astype(np.int16), f"r{i}_faps": r.faps.astype(np.int16),
                           f"r{i}_weights": r.weights.astype(np.float32), f"r{i}_scale": r.scale.astype(np.float32),
                           f"r{i}_bound": r.bound.astype(np.float32)})
        np.savez_compressed(path, regions=len(self.regions), **arrays, **{k: np.asarray(v) for k, v in facts.items()})


def fit_region(moved: np.ndarray, angles: np.ndarray, values: np.ndarray, fapu: list[Fapu] | Fapu,
               landmarks: np.ndarray, faps: np.ndarray, ridge: float, runs: np.ndarray | None = None) -> RegionMap:
    """Ridge fit of one region: ``moved`` ``(n, FACE_LANDMARKS, 3)``, ``angles`` ``(n, 3)``, ``values`` ``(n, F)`` in FAPU
    of the faces whose FAPU are ``fapu`` (one, or one per run with ``runs`` ``(n,)`` saying each frame's run).
    ``ridge`` is the penalty per sample on inputs scaled to unit spread."""
    landmarks, faps = np.asarray(landmarks), np.asarray(faps)
    x = design(np.asarray(moved)[:, landmarks], angles)
    units = [fapu] if isinstance(fapu, Fapu) else list(fapu)
    which = np.zeros(len(x), dtype=int) if runs is None else np.asarray(runs)
    targets = np.empty((len(x), len(faps)))
    for k, f in enumerate(units):
        targets[which == k] = displacements(np.asarray(values)[which == k], faps, f)
    scale = np.sqrt(np.mean(x * x, axis=0))
    scale[scale == 0] = 1.0
    x = x / scale
    weights = np.linalg.solve(x.T @ x + ridge * len(x) * np.eye(x.shape[1]), x.T @ targets)
    return RegionMap(landmarks, faps, weights, scale, 1.5 * np.abs(values).max(axis=0))


@lru_cache(maxsize=1)
def trained_map() -> FapMap | None:
    """The map shipped in ``data/fap_map.npz`` (None without it: the tracker then reads every FAP by its rule)."""
    if not DATA.exists():
        return None
    with np.load(DATA) as data:
        regions = tuple(RegionMap(data[f"r{i}_landmarks"].astype(np.int64), data[f"r{i}_faps"].astype(np.int64),
                                  data[f"r{i}_weights"].astype(np.float64), data[f"r{i}_scale"].astype(np.float64),
                                  data[f"r{i}_bound"].astype(np.float64)) for i in range(int(data["regions"])))
    return FapMap(regions)
