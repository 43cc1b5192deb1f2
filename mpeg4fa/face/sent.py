"""FDP case 4: play the sender's own mesh, moved by the sender's own FaceDefTables.

An FDP that carries a mesh and FaceDefTables says both what the face looks like and how each of
its FAPs deforms it. :func:`face_from_fdp` rigs that mesh (:func:`.custom.head_from_mesh`, the
FDP's feature points snapped to its vertices) and hands the tables to the ``tables`` deformer
(:mod:`.deformers.tables`), converted into the rigged head's frame: the rig turns the mesh into
the standard's axes and millimetres, so each displacement is turned and scaled the same way,
each ``coord_index`` follows its vertex, and the transforms act about the sender's origin.
FAPs without a table move the mesh as on any rigged face.
"""
from __future__ import annotations

import warnings

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.model import FaceModel


class TablesWarning(UserWarning):
    """Some of the sender's tables cannot be applied (FAP 1/2 tables, vertices no triangle uses)."""


def has_tables(fdp) -> bool:
    """Whether ``fdp`` is case 4: a mesh and tables that deform it."""
    return fdp.mesh is not None and bool(fdp.tables)


def face_from_fdp(fdp) -> FaceModel:
    """The sender's mesh rigged, moved by its tables where it has them (see the module docstring)."""
    from mpeg4fa.face.custom import head_from_mesh
    from mpeg4fa.face.deformers.tables import unused_tables

    if fdp.mesh is None:
        raise FaceError("the FDP carries no mesh to play", hint="play it on the generic head (it is calibrated)")
    mesh = fdp.mesh
    points = {label: p for label, p in zip(fdp.labels, np.asarray(fdp.points, dtype=np.float64))}
    head = head_from_mesh(mesh.vertices, mesh.triangles, points, uvs=mesh.uvs, name=fdp.name or "sent mesh")
    face = FaceModel(head)
    if not fdp.tables:
        return face
    skipped = unused_tables(fdp.tables)
    if skipped:
        warnings.warn(f"FDP tables of FAP {', '.join(map(str, skipped))} not applied: visemes and expressions "
                      "reach the face as low-level FAPs, whose tables move it", TablesWarning, stacklevel=2)
    tables, origin = in_head_frame(fdp.tables, head)
    return face.with_deformer("tables", tables=tables, origin=origin)


def in_head_frame(tables, head) -> tuple[tuple, np.ndarray]:
    """The tables with vertex indices, displacements and transforms in ``head``'s frame (see
    :func:`.custom.head_from_mesh`), and where the sender's origin lies there."""
    from mpeg4fa.fdp.model import FaceDefMesh, FaceDefTable, FaceDefTransform

    frame = head.info["frame"]
    rot, scale = frame["rotation"], frame["scale"]
    index = head.info["head_vertex"]
    origin = np.array([-frame["midline_x"], 0.0, 0.0]) * scale
    lost: set[int] = set()
    out = []
    for t in tables:
        meshes = []
        for m in t.meshes:
            here = index[m.coord_index] if len(m.coord_index) else m.coord_index
            keep = here >= 0
            lost.update(int(i) for i in m.coord_index[~keep])
            meshes.append(FaceDefMesh(here[keep], m.interval_borders, m.displacements[keep] @ rot.T * scale))
        transforms = []
        for f in t.transforms:
            axis = rot @ f.rotation[:3]
            transforms.append(FaceDefTransform(f.field, rotation=np.append(axis, f.rotation[3]),
                                               scale=np.abs(rot) @ f.scale, translation=rot @ f.translation * scale))
        out.append(FaceDefTable(t.fap, t.high_level_select, tuple(meshes), tuple(transforms)))
    if lost:
        warnings.warn(f"FDP tables move {len(lost)} vertices no triangle uses (e.g. {min(lost)}): left out",
                      TablesWarning, stacklevel=3)
    return tuple(out), origin


def played_face(fdp, *, method: str = "dffd") -> FaceModel:
    """The face a received FDP is played on: its own mesh and tables (case 4), else the generic head
    calibrated to its points (``method``). A case-4 mesh that cannot be rigged (e.g. it lacks the
    feature points a rig needs) is said in a :class:`TablesWarning` and the generic head is used."""
    if has_tables(fdp):
        try:
            return face_from_fdp(fdp)
        except FaceError as exc:
            warnings.warn(f"the FDP's own mesh cannot be played ({exc.message}); playing the generic head "
                          "calibrated to its points instead", TablesWarning, stacklevel=2)
    return FaceModel.default().calibrate(fdp, method=method)
