"""Face definition parameters (FDP): what a sender transmits so a decoder can fit its own head.

An :class:`Fdp` carries coordinates of any subset of the 84 MPEG-4 feature
points, optionally their texture coordinates, texture images, a whole face mesh
and per-FAP deformation tables (the BIFS FaceDefTables / FaceDefMesh /
FaceDefTransform nodes). The face engine calibrates its generic head to these
points; FAP streams then animate the calibrated head.

Three file forms, all read by :func:`load_fdp` by content:

* binary stream (``save_fdp(fdp, "x.fdp")``): compact, versioned, CRC-checked
  chunks, specified in ``spec/FDP_STREAM.md``;
* JSON (``save_fdp(fdp, "x.json")``): readable and hand-editable;
* Xface ``.fdp`` XML (read only): :func:`read_xface_fdp` then
  :meth:`XfaceFdp.to_fdp` with the mesh's vertices.

Building one for the encoder: :func:`fdp_from_mesh` from a user's mesh (e.g.
:func:`read_obj`) with marked feature points, or :func:`fdp_from_photos` from a
front and a side photo with annotated 2D points (:func:`read_points_json`), the
front photo going along as texture (:func:`texture_from_file`).

Every reader reports malformed content as an :class:`FdpError` that says where:
``path:line:column`` for the text forms, ``path: byte N`` for the binary one.
Work is bounded: a file is at most 256 MiB (:data:`mpeg4fa.fdp.errors.MAX_FILE_BYTES`;
devices are refused), JSON at most 32 Mi characters, Xface XML at most 200,000
elements, and every count in the binary form is checked against the bytes left.
"""
from mpeg4fa.fdp.binary import fdp_from_bytes, fdp_to_bytes
from mpeg4fa.fdp.build import (MIRROR_TWINS, fdp_from_mesh, fdp_from_photos, image_size, points_from_photos,
                               read_points_json, texture_from_file)
from mpeg4fa.fdp.errors import FdpError
from mpeg4fa.fdp.io import load_fdp, save_fdp, sniff_fdp
from mpeg4fa.fdp.json_form import fdp_from_json, fdp_to_json
from mpeg4fa.fdp.model import (FaceDefMesh, FaceDefTable, FaceDefTransform, Fdp, FdpMesh, FdpValueError,
                               TextureImage)
from mpeg4fa.fdp.obj import mesh_from_obj, read_obj
from mpeg4fa.fdp.xface import XfaceEntry, XfaceFdp, XfaceInfluence, read_xface_fdp, xface_from_xml

__all__ = [
    "Fdp", "FdpMesh", "TextureImage", "FaceDefTable", "FaceDefMesh", "FaceDefTransform", "FdpError",
    "FdpValueError", "load_fdp", "save_fdp", "sniff_fdp", "fdp_to_json", "fdp_from_json", "fdp_to_bytes",
    "fdp_from_bytes", "read_xface_fdp", "xface_from_xml", "XfaceFdp", "XfaceEntry", "XfaceInfluence",
    "read_obj", "mesh_from_obj", "fdp_from_mesh", "fdp_from_photos", "points_from_photos", "read_points_json",
    "texture_from_file", "image_size", "MIRROR_TWINS",
]
