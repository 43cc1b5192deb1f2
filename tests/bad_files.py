"""Files a reader must refuse with one located error: a missing file, a folder, random bytes,
empty files and whatever each format adds. Shared by the formats and FDP tests."""
from __future__ import annotations

from pathlib import Path

import numpy as np

FOLDER = object()
"""Stands for "make a folder of this name" in :func:`make_cases`."""


def make_cases(tmp_path: Path, suffix: str, extra: list[tuple[str, bytes, str]], seed: int = 0
               ) -> dict[str, tuple[Path, str]]:
    """name -> (path, words the error must say): the common bad paths with ``suffix``, then ``extra``."""
    common: list[tuple[str, object, str]] = [
        (f"missing{suffix}", None, "no such file"),
        (f"folder{suffix}", FOLDER, "is a directory"),
        (f"random{suffix}", np.random.default_rng(seed).integers(0, 256, 4096, dtype=np.uint8).tobytes(), ""),
    ]
    cases = {}
    for name, data, words in [*common, *extra]:
        path = tmp_path / name
        if data is FOLDER:
            path.mkdir()
        elif data is not None:
            path.write_bytes(data)
        cases[name] = (path, words)
    return cases
