"""One mesh being edited, with undo and redo as stacks of snapshots (edits never change a mesh).

The session takes a mesh only after :func:`~mpeg4fa.web.edits.check_vertices` passed on it, so a refused
load or edit leaves the model as it was and the model is always one the API can answer with."""
from __future__ import annotations

import threading
from typing import Callable

from mpeg4fa.web.edits import EditError, EditMesh, check_vertices

UNDO_LIMIT = 200


class Session:
    def __init__(self, mesh: EditMesh | None = None) -> None:
        self.mesh = mesh
        self.undo_stack: list[EditMesh] = []
        self.redo_stack: list[EditMesh] = []
        self.lock = threading.RLock()

    def require(self) -> EditMesh:
        if self.mesh is None:
            raise EditError("no model loaded", where="session", hint="load the head or upload a mesh first")
        return self.mesh

    def load(self, mesh: EditMesh) -> None:
        check_vertices(mesh.vertices)
        with self.lock:
            self.mesh, self.undo_stack, self.redo_stack = mesh, [], []

    def apply(self, op: Callable[[EditMesh], EditMesh]) -> EditMesh:
        with self.lock:
            new = op(self.require())
            check_vertices(new.vertices)
            self.undo_stack = (self.undo_stack + [self.mesh])[-UNDO_LIMIT:]
            self.redo_stack = []
            self.mesh = new
            return new

    def undo(self) -> EditMesh:
        with self.lock:
            if not self.undo_stack:
                raise EditError("nothing to undo", where="undo")
            self.redo_stack.append(self.mesh)
            self.mesh = self.undo_stack.pop()
            return self.mesh

    def redo(self) -> EditMesh:
        with self.lock:
            if not self.redo_stack:
                raise EditError("nothing to redo", where="redo")
            self.undo_stack.append(self.mesh)
            self.mesh = self.redo_stack.pop()
            return self.mesh
