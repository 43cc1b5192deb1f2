"""The suite's faces: one committed template head, stretched into faces whose FAPU differ.

A decoder that measures a FAPU on the wrong points, or scales a FAP with the wrong unit, shows
the right motion on one face by luck at most; on faces of other sizes and proportions it cannot.
So every face is the template (``conformance/faces/template.csv``: our own plausible adult head in
mm, +x the face's left, +y up, +z out of the face) under a per-axis scale, and one face keeps only
the points the FAPU and a few FAPs need, to check that a decoder copes with a partial FDP.
Points are rounded to 0.1 mm so the FDP files hold exact, reproducible numbers.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.fdp import Fdp, save_fdp
from mpeg4fa.spec import FAPU, FEATURE_POINTS

TEMPLATE = "faces/template.csv"

_MOUTH_GROUPS = ("2.", "8.")
"""Feature-point groups of the lips and jaw line (a wide mouth stretches them sideways)."""

_SUBSET = ("2.1", "2.2", "2.3", "2.4", "2.5", "3.1", "3.2", "3.3", "3.4", "3.5", "3.6", "4.1", "4.2",
           "7.1", "8.1", "8.2", "8.3", "8.4", "9.3", "9.15")
"""The subset face: the FAPU points (3.1-3.6, 9.15, 2.2, 8.3, 8.4) plus some the jaw, lip, brow and head FAPs move."""


@dataclass(frozen=True)
class FaceSpec:
    name: str
    description: str
    scale: tuple[float, float, float]
    mouth_width: float = 1.0
    labels: tuple[str, ...] | None = None  # None: all 84


FACES: tuple[FaceSpec, ...] = (
    FaceSpec("adult", "the template adult head, all 84 feature points", (1.0, 1.0, 1.0)),
    FaceSpec("child", "a child: the template at 0.75x with a mouth 1.3x wider (MW larger against ES, ENS, MNS)",
             (0.75, 0.75, 0.75), mouth_width=1.3),
    FaceSpec("long", "a long narrow face: 1.2x tall, 0.9x wide, 1.05x deep (ENS, MNS, IRISD larger against ES, MW)",
             (0.9, 1.2, 1.05)),
    FaceSpec("subset", "a large face (1.1x wide and deep, 1.05x tall, mouth 0.9x) with only 20 feature points: "
             "those of the FAPU and a few FAPs", (1.1, 1.05, 1.1), mouth_width=0.9, labels=_SUBSET),
)
FACE_NAMES = tuple(f.name for f in FACES)


def read_template(path: Path) -> dict[str, np.ndarray]:
    """``{label: (3,) mm}`` from the template CSV (label,x,y,z), every standard label once."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as exc:
        raise ConformanceError(f"cannot read the face template: {exc.strerror or exc}", where=str(path)) from None
    points = {r["label"]: np.array([float(r["x"]), float(r["y"]), float(r["z"])]) for r in rows}
    wanted = [p.label for p in FEATURE_POINTS]
    if sorted(points) != sorted(wanted):
        raise ConformanceError("the face template must list each of the 84 feature points once", where=str(path))
    return {label: points[label] for label in wanted}


def face_points(spec: FaceSpec, template: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The face's neutral feature points: the template scaled per axis, rounded to 0.1 mm."""
    out = {}
    for label, p in template.items():
        if spec.labels is not None and label not in spec.labels:
            continue
        q = p * np.asarray(spec.scale)
        if label.startswith(_MOUTH_GROUPS):
            q[0] *= spec.mouth_width
        out[label] = np.round(q, 1) + 0.0
    return out


def neutral_distances(points: dict[str, np.ndarray]) -> dict[str, float]:
    """The FAPU distances (IRISD0 ... MW0, mm) the FDP carries, measured as the spec's table defines them."""
    out = {}
    for f in FAPU.values():
        if f.point_a is None:
            continue
        axis = "xyz".index(f.axis)
        out[f.distance] = round(float(points[f.point_a][axis] - points[f.point_b][axis]), 9)
    return out


def build_fdp(spec: FaceSpec, template: dict[str, np.ndarray]) -> Fdp:
    points = face_points(spec, template)
    return Fdp.from_points(points, fapu=neutral_distances(points), name=f"conformance {spec.name}")


def write_faces(folder: Path, template: dict[str, np.ndarray]) -> dict[str, tuple[FaceSpec, dict[str, np.ndarray], str]]:
    """Write ``faces/<name>.fdp`` (binary FDP) for every face; returns name -> (spec, points, relative path)."""
    (folder / "faces").mkdir(parents=True, exist_ok=True)
    out = {}
    for spec in FACES:
        rel = f"faces/{spec.name}.fdp"
        save_fdp(build_fdp(spec, template), folder / rel)
        out[spec.name] = (spec, face_points(spec, template), rel)
    return out
