"""Layer 4, the choice of how a frame's FAP values pose the mesh.

Every deformer honours the same FAPU semantics (a FAP moves its feature point by value x FAPU
along the standard's direction); they differ in how the rest of the skin follows and in what
they cost. Each lives in its own module with a ``build(mesh, rig)`` that does the per-face
set-up once and returns a callable ``values (68,) -> Pose``; the registry below names them, so
that :class:`~mpeg4fa.face.model.FaceModel`, the CLI and the tools list the same choices.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.rig import Rig

Deformer = Callable[[np.ndarray], Pose]


@dataclass(frozen=True)
class DeformerKind:
    """One registered deformer: its name, the module that builds it and a line for ``--help``."""

    name: str
    module: str
    summary: str
    needs_face_units: bool = False
    options: tuple[str, ...] = ()
    """Keyword options its ``build`` takes."""
    listed: bool = True
    """Offered as a choice (``--deformer``, :func:`names`); the FDP tables' deformer is chosen by its FDP."""


KINDS: dict[str, DeformerKind] = {k.name: k for k in (
    DeformerKind("fap", "feature_points", "feature points and smooth Sibson weights (default)"),
    DeformerKind("arkit", "arkit", "the sculpted CC0 ARKit face units, corrected so feature points stay exact",
                 needs_face_units=True),
    DeformerKind("muscle", "muscle", "Waters linear muscles fitted to the FAPs, corrected so feature points stay exact"),
    DeformerKind("parabolic", "parabolic", "the feature-point deformer with spherical eyeballs and parabolic lid contours"),
    DeformerKind("blocks", "blocks", "eye and mouth blocks moving as least-squares affine (12-parameter elastic) fields",
                 options=("regions",)),
    DeformerKind("tables", "tables", "the FDP's own FaceDefTables (case 4) for the FAPs they define, "
                 "feature points for the rest", options=("tables", "origin"), listed=False),
)}


def names() -> tuple[str, ...]:
    """The deformer names a user chooses from, default first."""
    return tuple(name for name, k in KINDS.items() if k.listed)


def kind(name: str) -> DeformerKind:
    """The registered deformer ``name``, or a :class:`FaceError` listing the choices."""
    try:
        return KINDS[name]
    except KeyError:
        raise FaceError(f"unknown deformer {name!r}", hint=f"one of {', '.join(KINDS)}") from None


def build(name: str, mesh: HeadMesh, rig: Rig, **options) -> Deformer:
    """Set up deformer ``name`` for one neutral face (imported on first use: each has its own cost).

    ``options`` go to the deformer's own ``build`` (the block deformer's ``regions``: which blocks move
    as elastic blocks, the rest of the face as with the feature-point deformer)."""
    k = check(name, mesh, options)
    module = importlib.import_module(f"{__name__}.{k.module}")
    return module.build(mesh, rig, **options)


def check(name: str, mesh: HeadMesh, options: dict) -> DeformerKind:
    """The deformer ``name`` if it can pose ``mesh`` with ``options``, else a :class:`FaceError` saying why."""
    k = kind(name)
    if k.needs_face_units and mesh.face_units is None:
        raise FaceError(f"the {name} deformer needs a head with face units (the generic head has them)",
                        hint="use the feature-point deformer (deformer='fap')")
    unknown = [o for o in options if o not in k.options]
    if unknown:
        raise FaceError(f"the {name} deformer has no option {unknown[0]!r}",
                        hint=f"its options: {', '.join(k.options)}" if k.options else "it takes none")
    if options:  # their values too, by the deformer's own rule, before any set-up is paid for
        importlib.import_module(f"{__name__}.{k.module}").check_options(**options)
    return k
