"""Read one VRML 97 file with VTK in a process of its own: ``python -m mpeg4fa.web._vrml_worker FILE NAME OUT``.

Run by :func:`mpeg4fa.web.vrml.read_vrml`. VTK's OpenGL module (needed: without its overrides a USE'd
Shape crashes VTK) takes the calling thread's current GL context away, which breaks the renderer's
shared EGL context in the same process, and VTK's parser is a C++ library fed untrusted files; here
neither can harm the editor's server. Writes ``OUT`` (an ``.npz``: ``names`` and ``vertices_K`` /
``triangles_K`` per Shape) or prints ``{"error", "where", "hint"}`` as the last line of stdout and
exits 1.

VTK reports a syntax error only as text (the parser's own ``Error near line N``, counted from the line
after the ``#VRML`` header, and vtkOutputWindow messages), so both are captured around the import and
turned into one error at ``file:line``. A coordIndex outside the Shape's points has no line from VTK:
it is reported as ``file: shape N``.
"""
from __future__ import annotations

import json
import os
import re
import sys
import tempfile
from collections import Counter
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from mpeg4fa.extras import install_line
from mpeg4fa.web.edits import EditError

_VTK_LINE = re.compile(r"(?:Error near line|Error at line) (\d+):\s*(.*)")
_DEF_SHAPE = re.compile(rb"\bDEF\s+([^\s{}\[\]]+)\s+Shape\b")


def read_shapes(path: Path, filename: str) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``[(name, vertices (V, 3), triangles (T, 3))]``, one per Shape with an IndexedFaceSet, in file order."""
    data = path.read_bytes()
    try:
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (its overrides: without them a USE'd Shape crashes VTK)
        from vtkmodules.vtkIOImport import vtkVRMLImporter  # VTK takes ~0.3 s to import: only when a .wrl comes
    except ImportError as exc:
        raise EditError(f"VTK, which reads VRML here, does not load: {exc}", where=filename,
                        hint=f"{install_line('vrml')}, or convert the file to OBJ or GLB") from None

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
            if others:  # what is not VTK's goes where it was going
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


def main(argv: list[str]) -> int:
    path, filename, out = Path(argv[0]), argv[1], argv[2]
    try:
        shapes = read_shapes(path, filename)
    except EditError as exc:
        print(json.dumps({"error": exc.message, "where": exc.where, "hint": exc.hint}))
        return 1
    arrays = {"names": np.array([name for name, _, _ in shapes])}
    for k, (_, vertices, triangles) in enumerate(shapes):
        arrays[f"vertices_{k}"], arrays[f"triangles_{k}"] = vertices, triangles
    np.savez(out, **arrays)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
