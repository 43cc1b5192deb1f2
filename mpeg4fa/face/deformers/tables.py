"""FDP case 4: the sender's own FaceDefTables move its mesh, our rig moves what they leave alone.

An FDP may carry the sender's mesh and, per FAP, how that FAP deforms it (BIFS FaceDefTables,
:mod:`mpeg4fa.fdp.model`): piecewise-linear displacements of listed vertices over the FAP's value
in FAPU (FaceDefMesh), and a rotation, scale or translation of the whole mesh (FaceDefTransform).
A FAP with a table is the sender's to define, so here it moves the mesh by its table alone: the
feature-point deformer poses the face with that FAP at 0, then each table adds its displacements
(:meth:`~mpeg4fa.fdp.model.FaceDefMesh.displace`, so a vertex moves by exactly the table's amount
per FAP unit) and applies its transforms (:meth:`~mpeg4fa.fdp.model.FaceDefTransform.at`) about
the mesh's origin (option ``origin``: where the sender's origin lies on a rigged mesh), in FAP
order. FAPs without a table pose the face as the feature-point deformer does. Vertex indices are
the face's own (:mod:`mpeg4fa.face.sent` converts a sender's mesh and tables into a rigged head's).

FAP 1 and 2 tables (a viseme's or expression's own displacements, chosen by ``highLevelSelect``)
are not applied: visemes and expressions reach the face expanded into low-level FAPs
(:mod:`mpeg4fa.decoded`), whose tables then move it. :func:`unused_tables` says which a face skips.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from mpeg4fa.face.deformers import feature_points
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.rig import Rig

HIGH_LEVEL = (1, 2)


def check_options(tables: Sequence = (), origin: Sequence[float] | None = None) -> tuple:
    """``tables`` as a tuple of :class:`~mpeg4fa.fdp.model.FaceDefTable` (``origin``, where transforms
    act, must be three finite numbers)."""
    from mpeg4fa.fdp.model import FaceDefTable

    if origin is not None:
        o = np.asarray(origin, dtype=np.float64) if not isinstance(origin, str) else np.zeros(0)
        if o.shape != (3,) or not np.isfinite(o).all():
            raise FaceError(f"origin={origin!r} is not a point (x, y, z)", hint="the point the tables' transforms act about")

    if isinstance(tables, FaceDefTable):
        tables = (tables,)
    if not isinstance(tables, (tuple, list)) or not all(isinstance(t, FaceDefTable) for t in tables):
        raise FaceError(f"tables={tables!r} is not a list of FaceDefTable", hint="pass an FDP's tables (fdp.tables)")
    return tuple(tables)


def unused_tables(tables: Sequence) -> list[int]:
    """FAP numbers of the tables this deformer does not apply (FAP 1 and 2: see the module docstring)."""
    return sorted({t.fap for t in tables if t.fap in HIGH_LEVEL})


def _transform(p: np.ndarray, transform, value: float, origin: np.ndarray) -> None:
    """Apply one FaceDefTransform at FAP value ``value`` about ``origin`` to every row of ``p`` (in place)."""
    t = transform.at(value)
    if t.field == "rotation":
        axis = t.rotation[:3] / np.linalg.norm(t.rotation[:3])
        p[:] = origin + Rotation.from_rotvec(axis * t.rotation[3]).apply(p - origin)
    elif t.field == "scale":
        p[:] = origin + (p - origin) * t.scale
    else:
        p += t.translation


class TablesDeformer:
    """``values (68,) -> Pose``: the feature-point deformer for FAPs without a table, the tables for the rest."""

    def __init__(self, mesh: HeadMesh, rig: Rig, tables: Sequence, origin: Sequence[float] | None = None) -> None:
        self.rig = rig
        self.origin = np.zeros(3) if origin is None else np.asarray(origin, dtype=np.float64)
        self.tables = tuple(t for t in check_options(tables) if t.fap not in HIGH_LEVEL)
        n = mesh.n_vertices
        for t in self.tables:
            for m in t.meshes:
                if len(m.coord_index) and int(m.coord_index.max()) >= n:
                    raise FaceError(f"the table of FAP {t.fap} moves vertex {int(m.coord_index.max())}, "
                                    f"but the face has {n} vertices",
                                    hint="play the FDP's tables on a face built from the FDP's own mesh")
        self.driven = np.array(sorted({t.fap - 1 for t in self.tables}), dtype=np.int64)

    def __call__(self, values: np.ndarray) -> Pose:
        v = np.array(values, dtype=np.float64)
        rest = v.copy()
        rest[self.driven] = 0.0
        base = feature_points.deform(self.rig, rest)
        p = base.vertices
        for t in self.tables:
            value = v[t.fap - 1]
            if value == 0.0:
                continue
            for m in t.meshes:
                p[m.coord_index] += m.displace(value)
            for transform in t.transforms:
                _transform(p, transform, value, self.origin)
        return Pose(vertices=p, parts=base.parts, pupil_diameter=base.pupil_diameter, fp_vertex=base.fp_vertex)


def build(mesh: HeadMesh, rig: Rig, tables: Sequence = (), origin: Sequence[float] | None = None) -> TablesDeformer:
    return TablesDeformer(mesh, rig, tables, origin)
