"""Feature points that a FAP carries besides its own: documented couplings, kept as data.

The standard moves exactly one point per FAP, but some FAPs cannot read as
meant when their neighbours stay put: ``push_b_lip`` / ``push_t_lip`` (16/17)
move only the inner lip midpoints 2.3/2.2 forward, so rounded visemes (ou, oh,
Chinese o, u, uv) would bulge the inner edge of the lip while its outer border
(8.x) stays where it was. ``data/couplings.csv`` lists, per FAP, the extra
points and the fraction of the FAP's motion each follows, with the reason. The
FAP's own points still move exactly value x FAPU; the coupled ones are the
documented exceptions to "no other feature point moves".

:data:`PASSIVE_POINTS` are the other exception: the centres of the outer lids,
which no FAP names. Held fixed, they pinch the lid skin into a fold when the
brows rise or the cheeks lift; so they ride on the skin around them. The eye
corners (3.7, 3.8, 3.11, 3.12), which no FAP names either, give a little as the
lids close and ride on the eyes' pitch (:func:`.lids.lid_corners`, how far:
:mod:`.lid_folds`).
"""
from __future__ import annotations

import csv
from functools import lru_cache
from importlib import resources

import numpy as np

from mpeg4fa.face import motion
from mpeg4fa.face.fapu import Fapu
from mpeg4fa.spec import FAPS


PASSIVE_POINTS = ("3.9", "3.10", "3.13", "3.14")
"""Feature points no FAP names that move with the surrounding skin instead of anchoring it."""
SCALP_POINTS = ("11.1", "11.2", "11.3")
"""The hairline: no FAP names it and it anchors the skin's own weights (a brow raise stretches the
forehead below it), but the scalp slides over the skull. Held fixed, brows raised twice their extreme
(4.3 32 mm up, 32 mm below 11.3) pressed the forehead into it and folded 32 triangles; so where the fold
guard spreads a brow's raise wide, the hairline goes up with the skin (:attr:`.FoldGuard.scalp`: 11.1-11.3
about 13 mm at twice the extreme, 8 mm at 400, 0.01 mm or less at +-200, never down)."""


@lru_cache(maxsize=1)
def couplings() -> tuple[tuple[int, str, float], ...]:
    """(FAP, feature point label, fraction) rows of ``data/couplings.csv``."""
    with (resources.files("mpeg4fa.face") / "data" / "couplings.csv").open(encoding="utf-8") as f:
        return tuple((int(r["fap"]), r["feature_point"], float(r["fraction"])) for r in csv.DictReader(f))


def coupled_points(fap: int) -> dict[str, float]:
    """Label -> fraction of the points FAP ``fap`` carries besides its own."""
    return {label: fraction for f, label, fraction in couplings() if f == fap}


def add_couplings(translate: np.ndarray, index: dict[str, int], fapu: Fapu) -> None:
    """Add the coupled points' motion to the FAP -> feature point translation table (in place)."""
    for fap, label, fraction in couplings():
        if label not in index:
            continue
        record = FAPS[fap - 1]
        i = index[label]
        translate[3 * i:3 * i + 3, fap - 1] += fraction * fapu.unit(record.fapu) * motion.direction(fap)
