"""Golden image comparison shared by the render tests.

After an intended change of the look, rewrite the goldens with ``MPEG4FA_UPDATE_GOLDENS=1 pytest ...``
and look at them before committing. llvmpipe output may differ slightly between CPUs (vector
width), so images are compared with a tolerance.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from PIL import Image

GOLDEN = Path(__file__).with_name("golden")


def assert_matches_golden(image: np.ndarray, name: str) -> None:
    path = GOLDEN / name
    if os.environ.get("MPEG4FA_UPDATE_GOLDENS"):
        Image.fromarray(image).save(path)
    golden = np.asarray(Image.open(path).convert("RGB")).astype(int)
    diff = np.abs(image.astype(int) - golden)
    assert diff.mean() < 1.0, f"{path.name}: mean difference {diff.mean():.2f}"
    assert (diff.max(axis=2) > 24).mean() < 0.005, f"{path.name}: too many pixels differ"
