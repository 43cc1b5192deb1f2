"""A user's face mesh from a Wavefront OBJ file, the one mesh form every modelling tool writes.

Only what an FDP mesh holds is read: ``v`` (x y z; a w or vertex colours after
them are ignored), ``vt`` (u [v]) and ``f`` with corners ``v``, ``v/vt``,
``v//vn`` or ``v/vt/vn``, indices 1-based or negative (counting back from the
last ``v``/``vt`` above the face). Polygons are split into a fan of triangles
(exact for the convex polygons modellers export). The first ``o`` names the
mesh; every other statement (``vn``, ``g``, ``s``, ``usemtl``, ``l``...) and
``#`` comments are skipped.

An FdpMesh has one uv per vertex, so texture coordinates are kept only when
every vertex is used by a face and all its corners carry the same uv; a mesh
whose uvs are split along seams (or that has none) is read without uvs.

Every fault is an :class:`FdpError` at the line:column of the offending token.
"""
from __future__ import annotations

import math
import os
import re

import numpy as np

from mpeg4fa.fdp.errors import FdpError, read_bytes
from mpeg4fa.fdp.model import FdpMesh

_TOKEN = re.compile(r"\S+")
_INDEX_HINT = "OBJ indices count from 1; negative ones count back from the last one defined above the face"
# One row per face corner: resolved v, v as written, has vt, resolved vt, vt as written, line, column of v, of vt.
_V, _V_RAW, _HAS_VT, _VT, _VT_RAW, _LINE, _COL_V, _COL_VT = range(8)


def read_obj(path: str | os.PathLike[str]) -> FdpMesh:
    """Read the OBJ file at ``path`` as an :class:`FdpMesh`."""
    name = str(path)
    data = read_bytes(path)
    return mesh_from_obj(data, name)


def mesh_from_obj(text: str | bytes, path: str = "<string>") -> FdpMesh:
    """Parse OBJ text; ``path`` only names the source in error messages."""
    if isinstance(text, (bytes, bytearray, memoryview)):
        text = bytes(text).decode("utf-8", errors="replace")  # only ASCII numbers matter; names may be anything
    vertices: list[list[float]] = []
    uvs: list[list[float]] = []
    corners: list[tuple[int, ...]] = []
    sizes: list[int] = []
    name = ""
    for number, raw in enumerate(text.split("\n"), 1):
        line = raw.split("#", 1)[0].rstrip("\r")
        tokens = list(_TOKEN.finditer(line))
        if not tokens:
            continue
        key = tokens[0].group()
        if key == "v":
            vertices.append(_numbers(tokens, line, 3, 3, path, number, "a vertex needs x y z", "v 0.5 1.2 -3"))
        elif key == "vt":
            uv = _numbers(tokens, line, 1, 2, path, number, "a texture coordinate needs u [v]", "vt 0.25 0.75")
            uvs.append((uv + [0.0])[:2])
        elif key == "f":
            face = [_corner(m, len(vertices), len(uvs), path, number) for m in tokens[1:]]
            if len(face) < 3:
                raise FdpError(path, number, tokens[0].start() + 1,
                               f"a face needs at least 3 corners, got {len(face)}", "e.g. f 1 2 3")
            corners.extend(face)
            sizes.append(len(face))
        elif key == "o" and not name:
            name = line[tokens[0].end():].strip()
    if not sizes:
        raise FdpError.no_place(path, "no faces ('f' lines) in the OBJ file",
                                "export the mesh with its faces (triangles or polygons), not only its points")
    table = np.array(corners, dtype=np.int64)
    _check_range(table, _V, _V_RAW, _COL_V, len(vertices), "vertex", path)
    verts = np.array(vertices, dtype=np.float64).reshape(len(vertices), 3)
    return FdpMesh(verts, _fan(table[:, _V], np.array(sizes)), _per_vertex_uvs(table, uvs, len(verts), path),
                   name=name)


def _numbers(tokens: list[re.Match[str]], line: str, need: int, take: int, path: str, number: int, problem: str,
             example: str) -> list[float]:
    """The first ``take`` numbers after the statement keyword (at least ``need``), each finite."""
    values = tokens[1:1 + take]
    if len(values) < need:
        raise FdpError(path, number, len(line.rstrip()) + 1, f"{problem}, got {len(values)} number(s)",
                       f"e.g. {example}")
    out = []
    for m in values:
        try:
            value = float(m.group())
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            raise FdpError(path, number, m.start() + 1, f"{m.group()!r} is not a finite number",
                           f"e.g. {example}")
        out.append(value)
    return out


def _corner(m: re.Match[str], n_vertices: int, n_uvs: int, path: str, number: int) -> tuple[int, ...]:
    """One face corner as a row of the corner table (see the column names above)."""
    parts = m.group().split("/")
    if len(parts) > 3:
        raise FdpError(path, number, m.start() + 1, f"face corner {m.group()!r} has more than 3 parts",
                       "corners are v, v/vt, v//vn or v/vt/vn")
    v = _index(parts[0], n_vertices, path, number, m.start() + 1)
    col_vt = m.start() + len(parts[0]) + 2
    has_vt = len(parts) > 1 and parts[1] != ""
    vt = _index(parts[1], n_uvs, path, number, col_vt) if has_vt else (0, 0)
    return (v[0], v[1], int(has_vt), vt[0], vt[1], number, m.start() + 1, col_vt)


def _index(text: str, defined: int, path: str, number: int, column: int) -> tuple[int, int]:
    """(0-based index, index as written); negative indices are relative to the ``defined`` entries so far."""
    try:
        value = int(text)
    except ValueError:
        raise FdpError(path, number, column, f"{text!r} is not an index", _INDEX_HINT) from None
    if value == 0:
        raise FdpError(path, number, column, "index 0 does not exist", _INDEX_HINT)
    return (value - 1 if value > 0 else defined + value), value


def _check_range(table: np.ndarray, col: int, raw: int, col_at: int, count: int, what: str, path: str,
                 used: np.ndarray | None = None) -> None:
    """Fail at the first corner whose index (column ``col``) is outside ``count`` entries."""
    bad = (table[:, col] < 0) | (table[:, col] >= count)
    if used is not None:
        bad &= used
    if bad.any():
        row = table[int(np.argmax(bad))]
        written = int(row[raw])
        problem = (f"{what} index {written} points before the first {what}" if written < 0 else
                   f"{what} index {written} is out of range: the file has {count} {what}s")
        raise FdpError(path, int(row[_LINE]), int(row[col_at]), problem, _INDEX_HINT)


def _fan(corner_vertices: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """(T, 3) triangles (c0, ci, ci+1) of each polygon, polygons given as consecutive runs of ``sizes`` corners."""
    counts = sizes - 2
    first = np.repeat(np.cumsum(sizes) - sizes, counts)
    step = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    return np.stack([corner_vertices[first], corner_vertices[first + step + 1], corner_vertices[first + step + 2]],
                    axis=1)


def _per_vertex_uvs(table: np.ndarray, uvs: list[list[float]], n_vertices: int, path: str) -> np.ndarray | None:
    """One uv per vertex, or None when some corner has none, a vertex is unused or has two different uvs."""
    has = table[:, _HAS_VT].astype(bool)
    _check_range(table, _VT, _VT_RAW, _COL_VT, len(uvs), "texture coordinate", path, used=has)
    if not has.all():
        return None
    corner_uv = np.array(uvs, dtype=np.float64)[table[:, _VT]]
    per_vertex = np.full((n_vertices, 2), np.nan)
    per_vertex[table[:, _V]] = corner_uv
    if np.isnan(per_vertex).any() or not np.array_equal(per_vertex[table[:, _V]], corner_uv):
        return None
    return per_vertex
