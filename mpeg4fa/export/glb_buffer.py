"""The binary chunk of a GLB and the accessors that read it (pygltflib objects), 4-byte aligned.

Why its own module: every array of the export (positions, morph deltas, indices, key
times, weights, the PNG texture) goes through the same three steps (pad, add a buffer
view, add an accessor with the bounds glTF asks for), and morph deltas are mostly zero,
so they are stored sparse (or not at all) rather than dense.
"""
from __future__ import annotations

import numpy as np
import pygltflib as gl

_TYPES = {1: gl.SCALAR, 2: gl.VEC2, 3: gl.VEC3, 4: gl.VEC4}
_COMPONENTS = {np.dtype(np.float32): gl.FLOAT, np.dtype(np.uint32): gl.UNSIGNED_INT,
               np.dtype(np.uint16): gl.UNSIGNED_SHORT, np.dtype(np.uint8): gl.UNSIGNED_BYTE}
SPARSE_BELOW = 0.5
"""A morph target moving fewer than this share of a primitive's vertices is stored sparse."""


class GlbBuffer:
    """Collects bytes, buffer views and accessors for one ``pygltflib.GLTF2``."""

    def __init__(self, gltf: gl.GLTF2) -> None:
        self.gltf = gltf
        self.chunks: list[bytes] = []
        self.size = 0

    def view(self, data: bytes, target: int | None = None, stride: int | None = None) -> int:
        """A buffer view over ``data`` (appended at the next 4-byte boundary); its index."""
        pad = (-self.size) % 4
        if pad:
            self.chunks.append(b"\0" * pad)
            self.size += pad
        self.gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=self.size, byteLength=len(data),
                                                   target=target, byteStride=stride))
        self.chunks.append(data)
        self.size += len(data)
        return len(self.gltf.bufferViews) - 1

    def accessor(self, array: np.ndarray, *, target: int | None = None, bounds: bool = False,
                 normalized: bool | None = None) -> int:
        """A tightly packed accessor over ``array`` ((n,) or (n, k)); ``bounds`` adds min/max (POSITION, key times)."""
        a = np.ascontiguousarray(array)
        width = 1 if a.ndim == 1 else a.shape[1]
        view = self.view(a.tobytes(), target)
        return self._add(gl.Accessor(bufferView=view, componentType=_COMPONENTS[a.dtype], count=len(a),
                                     type=_TYPES[width], normalized=normalized, **(_bounds(a) if bounds else {})))

    def morph_target(self, deltas: np.ndarray) -> int:
        """A VEC3 float accessor of position deltas: none stored when all are 0, sparse when few move."""
        d = np.ascontiguousarray(deltas, np.float32)
        moved = np.flatnonzero(np.any(d != 0, axis=1))
        bounds = _bounds(d)
        if not len(moved):  # an accessor without a buffer view reads as zeros
            return self._add(gl.Accessor(byteOffset=None, componentType=gl.FLOAT, count=len(d), type=gl.VEC3, **bounds))
        if len(moved) >= SPARSE_BELOW * len(d):
            return self._add(gl.Accessor(bufferView=self.view(d.tobytes(), gl.ARRAY_BUFFER), componentType=gl.FLOAT,
                                         count=len(d), type=gl.VEC3, **bounds))
        index_type = np.uint16 if len(d) <= 0xFFFF else np.uint32
        indices = self.view(moved.astype(index_type).tobytes())
        values = self.view(d[moved].tobytes())
        sparse = gl.Sparse(count=len(moved), indices=gl.AccessorSparseIndices(bufferView=indices,
                                                                     componentType=_COMPONENTS[np.dtype(index_type)]),
                           values=gl.AccessorSparseValues(bufferView=values))
        return self._add(gl.Accessor(byteOffset=None, componentType=gl.FLOAT, count=len(d), type=gl.VEC3, sparse=sparse,
                                     **bounds))

    def blob(self) -> bytes:
        data = b"".join(self.chunks)
        return data + b"\0" * ((-len(data)) % 4)

    def _add(self, accessor: gl.Accessor) -> int:
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1


def _bounds(a: np.ndarray) -> dict:
    """min/max per component as glTF wants them (floats for float data, ints for integer data)."""
    rows = a.reshape(len(a), -1)
    cast = float if a.dtype.kind == "f" else int
    return {"min": [cast(x) for x in rows.min(axis=0)], "max": [cast(x) for x in rows.max(axis=0)]}
