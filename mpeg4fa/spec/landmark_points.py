"""Where each MPEG-4 feature point lies among a landmark model's landmarks: ``spec/landmark_points.csv``.

Each of the 84 feature points is one landmark, a weighted mean of landmarks, or "not seen" (the
tongue, teeth, ears and skull a photo does not show: they come from the generic head once it is
calibrated). Loaded once; the table's ``#`` header lines say the convention. A broken table is a
``ValueError`` naming the file and line, as for every table of ``spec/``.
"""
from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass

import numpy as np

from mpeg4fa.spec import FEATURE_POINTS
from mpeg4fa.spec._load import check, data_dir, split_list

__all__ = ["LandmarkSource", "LANDMARK_POINTS", "LANDMARK_SOURCES", "N_MODEL_LANDMARKS"]

_NAME = "landmark_points.csv"


def _model_landmarks() -> int:
    """How many landmarks the table's model gives, as its first comment line says ("... N landmarks ...")."""
    first = (data_dir() / _NAME).read_text(encoding="utf-8").split("\n", 1)[0]
    found = re.search(r"(\d+) landmarks", first)
    check(first.startswith("#") and found is not None, f"{_NAME}:1: the first comment must say 'N landmarks'")
    return int(found.group(1))


N_MODEL_LANDMARKS = _model_landmarks()
"""Landmarks of the model the table is written for (MediaPipe Face Mesh with irises: 478)."""
_COLUMNS = ["fp", "source", "landmarks", "weights", "notes"]
_SOURCES = ("landmark", "mean", "not seen")


@dataclass(frozen=True)
class LandmarkSource:
    """One feature point's source: ``indices`` weighted by ``weights`` (summing to 1); empty when not seen."""

    label: str
    source: str
    indices: tuple[int, ...]
    weights: tuple[float, ...]
    notes: str

    @property
    def seen(self) -> bool:
        return bool(self.indices)


def _rows() -> list[tuple[int, dict[str, str]]]:
    text = (data_dir() / _NAME).read_text(encoding="utf-8")
    lines = [(n, line) for n, line in enumerate(text.splitlines(), start=1) if not line.startswith("#")]
    reader = csv.reader(io.StringIO("\n".join(line for _, line in lines)))
    header = next(reader)
    check(header == _COLUMNS, f"{_NAME}: header {header} != {_COLUMNS}")
    return [(n, dict(zip(_COLUMNS, row))) for (n, _), row in zip(lines[1:], reader)]


def _source(line: int, row: dict[str, str]) -> LandmarkSource:
    where = f"{_NAME}:{line}"
    kind, indices = row["source"], tuple(int(i) for i in split_list(row["landmarks"]))
    check(kind in _SOURCES, f"{where}: source {kind!r} is not one of {_SOURCES}")
    check(all(0 <= i < N_MODEL_LANDMARKS for i in indices) and len(set(indices)) == len(indices),
          f"{where}: landmarks must be distinct indices 0..{N_MODEL_LANDMARKS - 1}")
    wanted = {"landmark": (1, 1), "mean": (2, N_MODEL_LANDMARKS), "not seen": (0, 0)}[kind]
    check(wanted[0] <= len(indices) <= wanted[1], f"{where}: a {kind!r} point has {len(indices)} landmarks")
    weights = np.array([float(w) for w in split_list(row["weights"])] or [1.0] * len(indices))
    check(len(weights) == len(indices) and bool(np.all(weights > 0)), f"{where}: one positive weight per landmark")
    weights = weights / weights.sum() if len(weights) else weights
    check(bool(row["notes"].strip()), f"{where}: say why in the notes")
    return LandmarkSource(row["fp"], kind, indices, tuple(float(w) for w in weights), row["notes"])


def _table() -> tuple[LandmarkSource, ...]:
    table = tuple(_source(line, row) for line, row in _rows())
    check([s.label for s in table] == [fp.label for fp in FEATURE_POINTS],
          f"{_NAME}: must list the 84 feature points once each, in feature_points.csv order")
    return table


LANDMARK_SOURCES: tuple[LandmarkSource, ...] = _table()
"""Every feature point's source, in ``feature_points.csv`` order."""
LANDMARK_POINTS: dict[str, LandmarkSource] = {s.label: s for s in LANDMARK_SOURCES if s.seen}
"""The feature points a photo shows, by label."""
