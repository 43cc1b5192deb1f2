"""One mesh being edited, with undo and redo as stacks of snapshots (edits never change a mesh)."""
from __future__ import annotations

import threading
from typing import Callable

from mpeg4fa.web.edits import EditError, EditMesh

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
        with self.lock:
            self.mesh, self.undo_stack, self.redo_stack = mesh, [], []

    def apply(self, op: Callable[[EditMesh], EditMesh]) -> EditMesh:
        with self.lock:
            new = op(self.require())
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
