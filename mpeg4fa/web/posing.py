"""Posing the mesh being edited through the face engine (:meth:`FaceModel.deform`).

A mesh loaded from a head keeps each vertex's index in it (``origin``): the head is posed and each
vertex moves by its own vertex's displacement. A foreign mesh is posed through the head
calibrated to its placed feature points (:meth:`FaceModel.calibrate`), each vertex moving as the
calibrated head's nearest vertex does, until the engine rigs any mesh itself (issue 17, item 3).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from mpeg4fa.decoded import clamp, shown_values
from mpeg4fa.face import FaceModel
from mpeg4fa.spec import EXPRESSION_PROFILES, FULL_INTENSITY, N_FAPS, VISEME_PROFILES
from mpeg4fa.web.edits import EditError, EditMesh


def held_in_range(faps: dict[int, float]) -> tuple[dict[int, float], list[str]]:
    """The low-level FAPs held inside what a face shows (:func:`mpeg4fa.decoded.clamp`), and what was changed, one
    line a FAP: the page's to say. As warnings they went to the server's console, one line a FAP every request
    (and catching them is process-wide, unsafe in FastAPI's thread pool)."""
    row = np.zeros(N_FAPS)
    for fap, value in faps.items():
        row[int(fap) - 1] = value
    held, report = clamp(row)
    return {fap: float(held[int(fap) - 1]) for fap in faps}, [item.message(None) for item in report]


def pose_values(faps: dict[int, float], viseme: str | None = None, expression: str | None = None,
                intensity: int = FULL_INTENSITY) -> np.ndarray:
    """The 68 values, by the decoder's rules (as ``mpeg4fa model pose`` does)."""
    vis = expr = None
    if viseme:
        group, _, name = viseme.rpartition(":")
        group = group or "mpeg4"
        if name not in VISEME_PROFILES.get(group, {}):
            raise EditError(f"unknown viseme {viseme!r}", where="viseme",
                            hint="MPEG-4: " + " ".join(VISEME_PROFILES["mpeg4"]))
        vis = (group, name)
    if expression:
        if expression not in EXPRESSION_PROFILES:
            raise EditError(f"unknown expression {expression!r}", where="expression",
                            hint="one of " + ", ".join(EXPRESSION_PROFILES))
        expr = (expression, intensity)
    return shown_values(dict(faps), viseme=vis, expression=expr)


def posed_vertices(mesh: EditMesh, head: FaceModel, values: np.ndarray, cache: dict | None = None) -> np.ndarray:
    """``mesh``'s vertices posed by ``values`` (68 FAPs)."""
    cache = {} if cache is None else cache
    if len(mesh.origin) and (mesh.origin >= 0).all() and mesh.origin.max() < head.mesh.n_vertices:
        face, origin = head, mesh.origin
        base = head.mesh.vertices
    else:
        from mpeg4fa.fdp import Fdp

        if len(mesh.points) < 6:
            raise EditError("place feature points first: a foreign mesh is posed through the head "
                            "calibrated to them", where="pose")
        key = ("calibrated", tuple(sorted(mesh.points.items())), mesh.vertices[list(mesh.points.values())].tobytes())
        if key not in cache:
            cache.clear()
            face = head.calibrate(Fdp.from_points({k: mesh.vertices[v] for k, v in mesh.points.items()}))
            cache[key] = (face, cKDTree(face.mesh.vertices).query(mesh.vertices)[1])
        face, origin = cache[key]
        base = face.mesh.vertices
    moved = face.deform(values).vertices - base
    return mesh.vertices + moved[origin]
