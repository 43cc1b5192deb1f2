"""The face a player shows, from the choices a user makes: which mesh, which FDP, which warp, skull and deformer.

One home for the rules that `mpeg4fa play`, `snapshot`, `export`, `serve` and the batch runner share:
the generic head, or a mesh with its feature points rigged like it (:meth:`FaceModel.from_mesh`);
calibrated to an FDP (a case-4 FDP without a mesh of ours plays its own mesh:
:func:`~mpeg4fa.face.sent.played_face`); the NURBS skull; then the deformer, except that an FDP's
own FaceDefTables stay when the default deformer is asked for.
"""
from __future__ import annotations

import os
from typing import TYPE_CHECKING, Sequence

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.model import FaceModel

if TYPE_CHECKING:
    from mpeg4fa.fdp import Fdp

PathLike = str | os.PathLike


def mesh_face(mesh_path: PathLike, points_path: PathLike) -> FaceModel:
    """An OBJ mesh and its feature-point JSON (label -> vertex index or [x, y, z]) rigged as the generic head is."""
    from pathlib import Path

    from mpeg4fa.fdp import FdpError, FdpValueError, read_obj
    from mpeg4fa.fdp.build import read_points_json

    mesh = read_obj(mesh_path)
    points = read_points_json(points_path)
    try:
        return FaceModel.from_mesh(mesh.vertices, mesh.triangles, points, uvs=mesh.uvs, name=Path(mesh_path).stem)
    except FdpValueError as exc:
        raise FdpError.no_place(str(points_path), exc.message) from None
    except FaceError as exc:  # the mesh and its points rig no face (points out of order...): say which files
        if exc.where:
            raise
        raise FaceError(exc.message, where=f"{mesh_path} + {points_path}", hint=exc.hint) from None


def assemble_face(*, fdp: PathLike | Fdp | None = None, method: str = "dffd", skull: str = "triangles",
                  face_mesh: PathLike | None = None, face_points: PathLike | None = None,
                  deformer: str | None = None, blocks: Sequence[str] | None = None) -> FaceModel:
    """The face to play: ``face_mesh`` + ``face_points`` or the generic head, calibrated to ``fdp`` (a file or
    an :class:`~mpeg4fa.fdp.Fdp`), with
    ``skull`` ("triangles" or "nurbs") and ``deformer`` (None keeps the face's own; ``blocks`` only with
    the blocks deformer)."""
    if (face_mesh is None) != (face_points is None):
        raise FaceError("a face mesh needs its feature points and the points their mesh",
                        where="face_points" if face_points is None else "face_mesh",
                        hint="give both: an OBJ and a JSON of label -> vertex index or [x, y, z]")
    if blocks is not None and deformer != "blocks":
        raise FaceError(f"blocks go with the blocks deformer, not {deformer}", where="blocks")
    own = mesh_face(face_mesh, face_points) if face_mesh is not None else None
    face = own or FaceModel.default()
    if fdp is not None:
        from mpeg4fa.face.sent import played_face
        from mpeg4fa.fdp import Fdp, load_fdp
        sent = fdp if isinstance(fdp, Fdp) else load_fdp(fdp)
        face = face.calibrate(sent, method=method) if own else played_face(sent, method=method)
    if skull == "nurbs":
        face = face.with_nurbs_skull()
    elif skull != "triangles":
        raise FaceError(f"no skull {skull!r}", where="skull", hint="triangles or nurbs")
    if deformer is None or (face.deformer == "tables" and deformer == "fap"):  # FDP case 4: the sender's tables stay
        return face
    return face.with_deformer(deformer, **({"regions": tuple(blocks)} if blocks is not None else {}))
