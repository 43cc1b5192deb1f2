"""Open and save FDP files, choosing the form by content (never trusting the file name when reading)."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

from numpy.typing import ArrayLike

from mpeg4fa.fdp.binary import MAGIC, fdp_from_bytes, fdp_to_bytes
from mpeg4fa.filetype import HEAD_BYTES, head_hex, refuse_foreign
from mpeg4fa.fdp.errors import FdpError, read_bytes
from mpeg4fa.fdp.json_form import fdp_from_json, fdp_to_json
from mpeg4fa.fdp.model import Fdp
from mpeg4fa.fdp.xface import xface_from_xml

_BOM = b"\xef\xbb\xbf"
_UTF16_BOMS = (b"\xff\xfe", b"\xfe\xff")


def sniff_fdp(data: bytes) -> str | None:
    """``"binary"``, ``"json"``, ``"xface"`` or None, from the first bytes.

    The binary test looks at the first 4 magic bytes only, so a stream whose
    line-ending magic bytes were mangled still reaches the binary reader, which
    explains what happened.
    """
    if data[:4] == MAGIC[:4]:
        return "binary"
    if data[:2] in _UTF16_BOMS:  # XML may be UTF-16 (expat reads it); JSON must not, and its reader says so
        head = data[:4096].decode("utf-16", "replace").lstrip("\ufeff \t\r\n").encode("utf-8", "replace")
    else:
        head = data[len(_BOM):] if data.startswith(_BOM) else data
        head = head[:4096].lstrip(b" \t\r\n")
    if head.startswith(b"{"):
        return "json"
    if head.startswith(b"<"):
        return "xface"
    return None


def load_fdp(path: str | os.PathLike[str], meshes: Mapping[str, ArrayLike] | None = None) -> Fdp:
    """Read a binary, JSON or Xface ``.fdp`` file, recognised by content.

    An Xface file names mesh vertices rather than coordinates, so it needs
    ``meshes`` (``{submesh name: (V, 3) vertices}``); without it the error says
    so. For the rest of an Xface file (influences, indices) use
    :func:`~mpeg4fa.fdp.xface.read_xface_fdp`.
    """
    return fdp_from_data(read_bytes(path), str(path), meshes)


def fdp_from_data(data: bytes, name: str, meshes: Mapping[str, ArrayLike] | None = None) -> Fdp:
    """:func:`load_fdp` of bytes already read (an upload): ``name`` is what its errors say where."""
    kind = sniff_fdp(data)
    if kind == "binary":
        return fdp_from_bytes(data, name)
    if kind == "json":
        return fdp_from_json(data, name)
    if kind == "xface":
        xface = xface_from_xml(data, name)
        if meshes is None:
            raise FdpError.no_place(name, "an Xface .fdp names mesh vertices, not coordinates",
                                    "pass meshes={submesh: vertices} to load_fdp, or use read_xface_fdp(path)"
                                    ".to_fdp(vertices)")
        return xface.to_fdp(meshes)
    if not data:
        raise FdpError.no_place(name, "the file is empty")
    refuse_foreign(data[:HEAD_BYTES], "an FDP file", lambda problem, hint: FdpError.at_byte(name, 0, problem, hint))
    raise FdpError.at_byte(name, 0, f"not an FDP file: starts with {head_hex(data)}, neither the binary magic, "
                           "JSON nor XML", "FDP files are binary (.fdp from save_fdp), JSON or Xface XML")


def save_fdp(fdp: Fdp, path: str | os.PathLike[str], *, float32: bool = False) -> None:
    """Write ``fdp``: JSON when the name ends in ``.json``, else the binary stream."""
    name = str(path)
    if name.lower().endswith(".json"):
        payload = fdp_to_json(fdp).encode("utf-8")
    else:
        payload = fdp_to_bytes(fdp, float32=float32)
    try:
        Path(path).write_bytes(payload)
    except OSError as exc:
        from mpeg4fa.errors import unwritable

        raise FdpError.no_place(name, *unwritable(exc)) from None
