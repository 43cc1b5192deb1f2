"""VRML 97 meshes (``.wrl``) read by VTK's vtkVRMLImporter: one triangle mesh per Shape, Transforms applied.

trimesh has no VRML reader, so VTK (the ``vrml`` extra of pyproject.toml) parses the file; every Shape whose geometry
is an IndexedFaceSet becomes one part (named after the Shape's DEF name when it has one, a USE of it
``NAME_2``...), its points moved by the Transforms above it and its polygons split into triangles by
vtkTriangleFilter. VTK reads nothing but the file itself (no Inline, no texture images, no Script:
checked with strace).

VTK runs in a child process (:mod:`._vrml_worker`): its OpenGL module takes the thread's current GL
context away from the renderer's shared EGL context, and a crash of its parser on a hostile file must
not take the editor's server with it. A syntax error comes back as one
:class:`~mpeg4fa.web.edits.EditError` at ``file:line``.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from mpeg4fa.extras import absent
from mpeg4fa.web.edits import EditError

HEADER = b"#VRML V2.0"
TIMEOUT = 120.0  # s for one file; a 62,500-vertex head takes about 1 s


def read_vrml(data: bytes, filename: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``[(name, vertices (V, 3), triangles (T, 3))]``, one per Shape with an IndexedFaceSet, in file order."""
    if not data.lstrip(b"\xef\xbb\xbf").startswith(HEADER):
        raise EditError("not a VRML 97 file: it must begin with '#VRML V2.0 utf8'", where=f"{filename}:1",
                        hint="VRML 1.0 is not read; export VRML 97 (VRML 2.0)")
    missing = absent("vrml", "vtkmodules")
    if missing is not None:
        raise EditError(missing.message, where=filename, hint=f"{missing.hint}; or convert the file to OBJ or GLB")
    with tempfile.TemporaryDirectory(prefix="mpeg4fa-vrml-") as tmp:
        path, out = Path(tmp) / "upload.wrl", Path(tmp) / "shapes.npz"  # vtkVRMLImporter reads files only
        path.write_bytes(data)
        try:
            done = subprocess.run([sys.executable, "-m", "mpeg4fa.web._vrml_worker", str(path), filename, str(out)],
                                  capture_output=True, text=True, timeout=TIMEOUT)
        except subprocess.TimeoutExpired:
            raise EditError(f"VTK took longer than {TIMEOUT:.0f} s to read the file", where=filename,
                            hint="convert it to OBJ or GLB") from None
        if done.returncode == 0 and out.is_file():
            with np.load(out) as shapes:
                return [(str(name), shapes[f"vertices_{k}"], shapes[f"triangles_{k}"])
                        for k, name in enumerate(shapes["names"])]
    lines = done.stdout.strip().splitlines()
    try:
        fault = json.loads(lines[-1]) if lines else {}
    except json.JSONDecodeError:
        fault = {}
    if "error" in fault:
        raise EditError(fault["error"], where=fault.get("where") or filename, hint=fault.get("hint", ""))
    tail = (done.stderr.strip().splitlines() or [f"exit status {done.returncode}"])[-1]
    raise EditError(f"VTK failed to read the VRML file ({tail})", where=filename,
                    hint="check the file in another VRML viewer, or convert it to OBJ or GLB")
