"""VRML 97 meshes (``.wrl``) read by VTK's vtkVRMLImporter: one triangle mesh per Shape, Transforms applied.

trimesh has no VRML reader, so VTK (pinned in pyproject.toml) parses the file; every Shape whose geometry
is an IndexedFaceSet becomes one part (named after the Shape's DEF name when it has one, a USE of it
``NAME_2``...), its points
moved by the Transforms above it and its polygons split into triangles by vtkTriangleFilter. VTK reads
nothing but the file itself (no Inline, no texture images, no Script: checked with strace).

VTK reports a syntax error only as text (the parser's own ``Error near line N``, counted from the line
after the ``#VRML`` header, and vtkOutputWindow messages), so both are captured around the import and
turned into one :class:`~mpeg4fa.web.edits.EditError` at ``file:line``. A coordIndex outside the Shape's
points has no line from VTK: it is reported as ``file: shape N``.
"""
from __future__ import annotations

import os
import re
import sys
import tempfile
import threading
from collections import Counter
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from mpeg4fa.web.edits import EditError

HEADER = b"#VRML V2.0"
_LOCK = threading.Lock()  # the import redirects the process's stderr and vtk's global output window
_VTK_LINE = re.compile(r"(?:Error near line|Error at line) (\d+):\s*(.*)")
_DEF_SHAPE = re.compile(rb"\bDEF\s+([^\s{}\[\]]+)\s+Shape\b")


def read_vrml(data: bytes, filename: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``[(name, vertices (V, 3), triangles (T, 3))]``, one per Shape with an IndexedFaceSet, in file order."""
    if not data.lstrip(b"\xef\xbb\xbf").startswith(HEADER):
        raise EditError("not a VRML 97 file: it must begin with '#VRML V2.0 utf8'", where=f"{filename}:1",
                        hint="VRML 1.0 is not read; export VRML 97 (VRML 2.0)")
    try:
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (its overrides: without them a USE'd Shape crashes VTK)
        from vtkmodules.vtkIOImport import vtkVRMLImporter  # VTK takes ~0.3 s to import: only when a .wrl comes
    except ImportError as exc:
        raise EditError(f"VTK, which reads VRML here, does not load: {exc}", where=filename,
                        hint="reinstall mpeg4fa (it pins vtk), or convert the file to OBJ or GLB") from None

    with tempfile.TemporaryDirectory(prefix="mpeg4fa-vrml-") as tmp:
        path = Path(tmp) / "upload.wrl"  # vtkVRMLImporter reads files only
        path.write_bytes(data)
        importer = vtkVRMLImporter()
        importer.SetFileName(str(path))
        with _captured_errors() as messages:
            importer.Update()
    renderer = importer.GetRenderer()
    _raise_reported(messages, filename)
    names = {}  # the geometry a DEF'd Shape's actor draws -> the DEF name (a USE'd copy draws the same one)
    for raw in _DEF_SHAPE.findall(data):
        actor = importer.GetVRMLDEFObject(raw.decode("utf-8", "replace"))
        if actor is not None and actor.GetMapper() is not None and actor.GetMapper().GetInput() is not None:
            names[actor.GetMapper().GetInput().GetAddressAsString("vtkObject")] = raw.decode("utf-8", "replace")
    shapes, seen = [], Counter()
    actors = renderer.GetActors() if renderer is not None else None
    if actors is not None:
        actors.InitTraversal()
        for number in range(1, actors.GetNumberOfItems() + 1):
            actor = actors.GetNextActor()
            mesh = _triangles(actor, filename, number)
            if mesh is None:
                continue
            name = names.get(actor.GetMapper().GetInput().GetAddressAsString("vtkObject"), f"shape_{number}")
            seen[name] += 1
            shapes.append((name if seen[name] == 1 else f"{name}_{seen[name]}", *mesh))
    if not shapes:
        raise EditError("the VRML file holds no IndexedFaceSet with faces", where=filename,
                        hint="each Shape needs geometry IndexedFaceSet "
                             "{ coord Coordinate { point [...] } coordIndex [...] }")
    return shapes


def _triangles(actor, filename: str, number: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The actor's polygons as world-space (vertices, triangles); None for a Shape without faces."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkFiltersCore import vtkTriangleFilter

    mapper = actor.GetMapper()
    poly = mapper.GetInput() if mapper is not None else None
    if poly is None or poly.GetPoints() is None or poly.GetPolys().GetNumberOfCells() == 0:
        return None
    points = vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)
    corners = vtk_to_numpy(poly.GetPolys().GetConnectivityArray())
    if len(corners) and (corners.min() < 0 or corners.max() >= len(points)):
        bad = int(corners[(corners < 0) | (corners >= len(points))][0])
        raise EditError(f"coordIndex {bad} is out of range: the Shape has {len(points)} points",
                        where=f"{filename}: shape {number}", hint="coordIndex counts the Coordinate points from 0")
    split = vtkTriangleFilter()
    split.SetInputData(poly)
    split.PassVertsOff()
    split.PassLinesOff()
    split.Update()
    out = split.GetOutput()
    cells = out.GetPolys()
    offsets = vtk_to_numpy(cells.GetOffsetsArray())
    if len(offsets) < 2:
        return None
    triangles = vtk_to_numpy(cells.GetConnectivityArray()).astype(np.int64).reshape(-1, 3)
    vertices = vtk_to_numpy(out.GetPoints().GetData()).astype(np.float64)
    matrix = actor.GetMatrix()
    m = np.array([[matrix.GetElement(r, c) for c in range(4)] for r in range(4)])
    return vertices @ m[:3, :3].T + m[:3, 3], triangles


@contextmanager
def _captured_errors():
    """Collect what VTK writes (its output window and the parser's stderr) into the yielded list."""
    from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow

    messages: list[str] = []
    with _LOCK:
        window = vtkStringOutputWindow()
        previous = vtkOutputWindow.GetInstance()
        vtkOutputWindow.SetInstance(window)
        sys.stderr.flush()
        saved = os.dup(2)
        with tempfile.TemporaryFile() as sink:
            os.dup2(sink.fileno(), 2)
            try:
                yield messages
            finally:
                os.dup2(saved, 2)
                os.close(saved)
                vtkOutputWindow.SetInstance(previous)
                sink.seek(0)
                text = sink.read().decode("utf-8", "replace")
                others = [line for line in text.splitlines() if not (_VTK_LINE.search(line) or "vtk" in line)]
                if others:  # what another thread wrote meanwhile goes where it was going
                    sys.stderr.write("\n".join(others) + "\n")
                messages += text.splitlines() + window.GetOutput().splitlines()


def _raise_reported(messages: list[str], filename: str) -> None:
    """One located error for the first syntax error VTK reported (its line + 1: VTK skips the header)."""
    for line in messages:
        found = _VTK_LINE.search(line)
        if found:
            problem = found.group(2).strip().rstrip(".") or "syntax error"
            raise EditError(f"cannot read the VRML file: {problem}", where=f"{filename}:{int(found.group(1)) + 1}",
                            hint="VRML 97 nodes with their fields; only IndexedFaceSet geometry is used")
