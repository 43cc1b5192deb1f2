"""A user's face mesh from a Wavefront OBJ file, the one mesh form every modelling tool writes, read by trimesh.

trimesh's OBJ reader (:func:`trimesh.exchange.obj.load_obj`) makes the arrays. A feature point names a
vertex by its index in the file, so this module hands trimesh the file in a form where its indices are
the file's own, and refuses, at the line:column of the statement, what trimesh would read wrong:

* ``#`` comments are cut and ``usemtl``/``mtllib`` lines dropped before trimesh sees the text (it reads
  a comment after a face as an index, and splits the faces of each material into a mesh of its own);
  normal references (``v//vn``, ``v/vt/vn``) are dropped too (an FdpMesh has no normals, and trimesh would
  split a vertex per normal).
* Positions and faces are read with ``maintain_order`` and no texture references, the one way trimesh
  keeps every ``v`` line as vertex ``i`` (unused ones included); the result is checked against the
  file's count of ``v`` lines and of triangles.
* Texture coordinates come from a second read with the ``vt`` references: trimesh then gives one vertex
  per distinct (v, vt) pair, and its uvs are kept only when that is exactly the file's vertex list, i.e.
  every vertex is used by a face and all its corners carry the same uv (an FdpMesh has one uv per vertex).
  A mesh whose uvs are split along seams (or that has none) is read without uvs, and so is one whose faces
  use negative indices (trimesh pairs ``-2/1`` and ``3/1`` as two vertices).
* trimesh counts a negative (relative) index back from the file's last ``v``/``vt``, not from the face's
  place; such a face above more ``v``/``vt`` lines is refused, as are index 0, a malformed ``v``/``vt``/``f``
  statement and an index out of range.

Polygons are triangulated by trimesh (a fan from the first corner; a quad as (0,1,2), (2,3,0); in a file
of quads only, all first halves come before all second halves). The first ``o`` names the mesh;
:func:`mesh_and_groups_from_obj` also names each triangle's ``g`` group (or ``o`` object); ``vn``, ``s``,
``l`` and other statements are ignored. The statement checks are regular expressions over the text (they
locate faults; trimesh reads); a disagreement between trimesh's result and the file's counts, which the
checks should make impossible, is reported for the whole file (trimesh gives no line).
"""
from __future__ import annotations

import io
import math
import os
import re

import numpy as np

from mpeg4fa.fdp.errors import FdpError, read_bytes
from mpeg4fa.filetype import HEAD_BYTES, refuse_foreign
from mpeg4fa.fdp.model import MAX_COORDINATE, FdpMesh, first_unbounded

_INDEX_HINT = "OBJ indices count from 1; negative ones count back from the last one defined above the face"
# A number, matched one way only: "[0-9]+\.?[0-9]*" matched "4333" four ways, so a line of many numbers that
# then failed backtracked exponentially (fuzz obj:39238: a 1 kB file ran past 10 s).
_NUM = r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?"
_CORNER = r"-?[0-9]+(?:/-?[0-9]*(?:/-?[0-9]*)?)?"
_WS = r"[ \t\r]"
# First statement of each kind that is not well formed (checked by regex, located by _explain_*).
_BAD_V = re.compile(rf"(?m)^{_WS}*v(?={_WS}|$)(?!(?:{_WS}+{_NUM}){{3,}}{_WS}*$)")
_BAD_VT = re.compile(rf"(?m)^{_WS}*vt(?={_WS}|$)(?!(?:{_WS}+{_NUM}){{1,}}{_WS}*$)")
_BAD_F = re.compile(rf"(?m)^{_WS}*f(?={_WS}|$)(?!(?:{_WS}+{_CORNER}){{3,}}{_WS}*$)")
_STATEMENT = {key: re.compile(rf"(?m)^{_WS}*{key}{_WS}") for key in ("v", "vt", "f")}
_FACE_LINE = re.compile(rf"(?m)^{_WS}*f{_WS}[^\n]*")
_IN_FACE = rf"(?m)^{_WS}*f{_WS}[^\n]*?"
_ZERO_ANY = re.compile(r"[ \t\r/]-?0+(?![\w.])")  # fast pre-checks over the face lines alone
_ZERO = re.compile(_IN_FACE + r"(?<![\w.-])(-?0+)(?![\w.])")
_NEG_ANY = {"v": re.compile(r"[ \t\r]-[0-9]"), "vt": re.compile(r"/-[0-9]")}
_NEG = {"v": re.compile(_IN_FACE + r"(?<![\w/-])(-[0-9]+)"), "vt": re.compile(_IN_FACE + r"(?<![\w/-])-?[0-9]+/(-[0-9]+)")}
_INDEX = {"v": re.compile(r"(?<![\w/-])(-?[0-9]+)"), "vt": re.compile(r"(?<![\w/-])-?[0-9]+/(-?[0-9]+)")}
_GROUP, _OBJECT = re.compile(r"(?m)^g "), re.compile(r"(?m)^o ")
_NAME = re.compile(rf"(?m)^{_WS}*o{_WS}+([^\n]*\S)")


MAX_OBJ_BYTES = 32 << 20
"""Largest OBJ read (32 MiB, about 600,000 vertices with their faces): parsing takes ~17 bytes of memory
and ~0.7 s per byte-MB of text (4.5 MB: 3 s, +80 MB), so this bounds a mesh at ~25 s and ~0.6 GB."""


def read_obj(path: str | os.PathLike[str]) -> FdpMesh:
    """Read the OBJ file at ``path`` as an :class:`FdpMesh` (at most :data:`MAX_OBJ_BYTES`)."""
    name = str(path)
    data = read_bytes(path, MAX_OBJ_BYTES, "an OBJ mesh")
    return mesh_from_obj(data, name)


def mesh_from_obj(text: str | bytes, path: str = "<string>") -> FdpMesh:
    """Parse OBJ text (with trimesh); ``path`` only names the source in error messages."""
    return _read(text, path, groups=False)[0]


def mesh_and_groups_from_obj(text: str | bytes, path: str = "<string>") -> tuple[FdpMesh, list[str]]:
    """:func:`mesh_from_obj` and, per triangle, the name of its ``g`` group (or, in a file without groups,
    of its ``o`` object; ``""`` in a file with neither), as trimesh splits them: how a downloaded head names
    its skin, eyes and teeth."""
    return _read(text, path, groups=True)  # type: ignore[return-value]


def _read(text: str | bytes, path: str, groups: bool) -> tuple[FdpMesh, list[str] | None]:
    if len(text) > MAX_OBJ_BYTES:
        raise FdpError.no_place(path, f"the OBJ text is {len(text):,} bytes, more than the {MAX_OBJ_BYTES:,} read",
                                "decimate the mesh; a face needs far fewer than 600,000 vertices")
    if isinstance(text, (bytes, bytearray, memoryview)):
        refuse_foreign(bytes(text[:HEAD_BYTES]), "an OBJ mesh", lambda problem, hint: FdpError.no_place(path, problem, hint))
        text = bytes(text).decode("utf-8", errors="replace")  # only ASCII numbers matter; names may be anything
    plain = re.sub(r"#[^\n]*", "", text)  # same lines and columns as the file, for locating faults
    _check_statements(plain, path)
    counts = {key: len(pattern.findall(plain)) for key, pattern in _STATEMENT.items()}
    if not counts["f"]:
        raise FdpError.no_place(path, "no faces ('f' lines) in the OBJ file",
                                "export the mesh with its faces (triangles or polygons), not only its points")
    faces_text = "\n".join(m.group() for m in _FACE_LINE.finditer(plain))
    _check_indices(plain, faces_text, path)
    feed = re.sub(rf"(?m)^{_WS}+|^(?:usemtl|mtllib)\b[^\n]*", "", plain).replace("\t", " ").replace("\r", "")
    sizes = [len(line.split()) - 1 for line in faces_text.split("\n")]
    triangles = sum(sizes) - 2 * len(sizes)
    slashes = faces_text.count("/")
    if slashes == 2 * sum(sizes):  # every corner v/vt/vn or v//vn: drop the last part (and a bare //)
        feed = re.sub(r"/-?[0-9]*(?=[ \n]|$)", "", re.sub(r"//-?[0-9]*", "", feed))
    elif re.search(r"[0-9]/-?[0-9]*/", faces_text):  # some corners with normals: v/vt/vn -> v/vt, v//vn -> v
        feed = re.sub(r"(/-?[0-9]+)/-?[0-9]*|//-?[0-9]*", r"\1", feed)
    plain_feed = re.sub(r"/-?[0-9]*", "", feed)
    vertices, faces, _ = _trimesh_read(plain_feed, plain, counts, triangles, path, uv=False)
    if first_unbounded(vertices) is not None:
        _locate_unbounded(plain, "v", path)
    names = _groups(plain_feed, faces, path) if groups else None
    uvs = None
    if counts["vt"] and "/" in feed:
        try:
            v_uv, f_uv, uv = _trimesh_read(feed, plain, counts, triangles, path, uv=True)
        except FdpError:
            uv = None  # no usable texture pairs (e.g. some corners have none): read without uvs
        if uv is not None and len(v_uv) == len(vertices) and np.array_equal(f_uv, faces):
            uvs = uv  # trimesh's (v, vt) pairs are exactly the file's vertices
            if first_unbounded(uvs) is not None:
                _locate_unbounded(plain, "vt", path)
        else:
            _locate_range(plain, counts, path)  # trimesh drops uvs it cannot index: say which one
    name = _NAME.search(plain)
    return FdpMesh(vertices, faces, uvs, name=name.group(1).strip() if name else ""), names


def _groups(feed: str, faces: np.ndarray, path: str) -> list[str]:
    """Per triangle of ``faces`` (the file's order), the name of the o/g group trimesh puts it in (matched by
    corners: of a triangle repeated in two groups, either copy may take either name)."""
    by_group = _GROUP.search(feed) is not None
    if not by_group and not _OBJECT.search(feed):
        return [""] * len(faces)
    import trimesh  # here, not at the top: a fifth of a second of every start that reads no OBJ file

    try:
        scene = trimesh.load(io.StringIO(feed), file_type="obj", force="scene", process=False, maintain_order=True,
                             skip_materials=True, group_material=False, split_objects=not by_group,
                             split_groups=by_group)
    except Exception as exc:  # the same text read once already: only a trimesh fault
        raise FdpError.no_place(path, f"trimesh cannot split the OBJ file into its groups: {exc}") from None
    parts = [(str(name), np.asarray(g.faces, np.int64)) for name, g in scene.geometry.items()
             if isinstance(g, trimesh.Trimesh)]
    rows = np.concatenate([faces] + [f for _, f in parts])
    _, key = np.unique(rows, axis=0, return_inverse=True)
    key = key.reshape(-1)
    slots: dict[int, list[int]] = {}
    for i, k in enumerate(key[:len(faces)].tolist()):
        slots.setdefault(k, []).append(i)
    out, at = [""] * len(faces), len(faces)
    for name, f in parts:  # each group triangle takes the first file triangle with the same corners
        for k in key[at:at + len(f)].tolist():
            if slots.get(k):
                out[slots[k].pop(0)] = name
        at += len(f)
    return out


def _trimesh_read(feed: str, plain: str, counts: dict[str, int], triangles: int, path: str,
                  uv: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(vertices, triangles, per-vertex uvs or None) as trimesh reads ``feed``, checked against the file."""
    import trimesh  # (see _groups)

    try:
        scene = trimesh.load(io.StringIO(feed), file_type="obj", force="scene", process=False,
                             maintain_order=not uv, skip_materials=True, group_material=False)
        geoms = [g for g in scene.geometry.values() if isinstance(g, trimesh.Trimesh)]
    except Exception as exc:  # any reader fault is the file's: an index out of range is found for the message
        _locate_range(plain, counts, path)
        raise FdpError.no_place(path, f"trimesh cannot read the OBJ file: {exc}", _INDEX_HINT) from None
    if len(geoms) != 1:
        raise FdpError.no_place(path, f"trimesh read {len(geoms)} meshes from the file, expected 1",
                                "export the face as one object")
    mesh = geoms[0]
    vertices, faces = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
    if len(faces) != triangles:
        raise FdpError.no_place(path, f"trimesh read {len(faces)} triangles where the faces make {triangles}",
                                "report this file: trimesh skipped or split faces")
    if not uv and len(vertices) != counts["v"]:
        raise FdpError.no_place(path, f"trimesh read {len(vertices)} vertices where the file has {counts['v']}"
                                " 'v' lines, which would shift feature point indices",
                                "report this file: trimesh did not keep the vertex order")
    if len(faces) and faces.max() >= len(vertices):
        _locate_range(plain, counts, path)
        raise FdpError.no_place(path, "trimesh read a face index past the last vertex", _INDEX_HINT)
    coords = getattr(mesh.visual, "uv", None)
    return vertices, faces, None if coords is None else np.asarray(coords, np.float64)[:, :2]


def _check_statements(plain: str, path: str) -> None:
    """Refuse the first malformed ``v``, ``vt`` or ``f`` statement, at its line:column."""
    found = [(m.start(), key, pattern) for key, pattern in (("v", _BAD_V), ("vt", _BAD_VT), ("f", _BAD_F))
             for m in [pattern.search(plain)] if m]
    if not found:
        return
    start, key, _ = min(found)
    number, line, offset = _line_at(plain, start)
    tokens = list(re.finditer(r"\S+", line))
    if key == "f":
        _explain_face(tokens, line, path, number)
    need, problem, example = (3, "a vertex needs x y z", "v 0.5 1.2 -3") if key == "v" else \
        (1, "a texture coordinate needs u [v]", "vt 0.25 0.75")
    for m in tokens[1:1 + (3 if key == "v" else 2)]:
        try:
            ok = math.isfinite(float(m.group()))
        except ValueError:
            ok = False
        if not ok:
            raise FdpError(path, number, m.start() + 1, f"{m.group()!r} is not a finite number", f"e.g. {example}")
    if len(tokens) - 1 < need:
        raise FdpError(path, number, len(line.rstrip()) + 1, f"{problem}, got {len(tokens) - 1} number(s)",
                       f"e.g. {example}")
    raise FdpError(path, number, tokens[-1].start() + 1, f"cannot read {tokens[-1].group()!r}", f"e.g. {example}")


def _explain_face(tokens: list[re.Match[str]], line: str, path: str, number: int) -> None:
    """Raise the fault of a malformed face line (a bad corner, fewer than 3 corners)."""
    for m in tokens[1:]:
        parts = m.group().split("/")
        if len(parts) > 3:
            raise FdpError(path, number, m.start() + 1, f"face corner {m.group()!r} has more than 3 parts",
                           "corners are v, v/vt, v//vn or v/vt/vn")
        column = m.start() + 1
        for i, part in enumerate(parts):
            if (part or i == 0) and not re.fullmatch(r"-?[0-9]+", part):
                raise FdpError(path, number, column, f"{part!r} is not an index", _INDEX_HINT)
            column += len(part) + 1
    raise FdpError(path, number, tokens[0].start() + 1, f"a face needs at least 3 corners, got {len(tokens) - 1}",
                   "e.g. f 1 2 3")


def _check_indices(plain: str, faces_text: str, path: str) -> None:
    """Refuse the indices trimesh would silently read wrong: 0, and negative ones above more v/vt lines.
    (The cheap searches run over the face lines alone; the file is searched only to locate a hit.)"""
    if _ZERO_ANY.search(faces_text):
        zero = _ZERO.search(plain)
        number, _, offset = _line_at(plain, zero.start(1))
        raise FdpError(path, number, offset + 1, "index 0 does not exist", _INDEX_HINT)
    for key in ("v", "vt"):
        neg = _NEG[key].search(plain) if _NEG_ANY[key].search(faces_text) else None
        last = max((m.start() for m in _STATEMENT[key].finditer(plain)), default=-1) if neg else -1
        if neg and neg.start(1) < last:
            number, _, offset = _line_at(plain, neg.start(1))
            raise FdpError(path, number, offset + 1,
                           f"a relative (negative) index in a face above further '{key}' lines: "
                           f"trimesh counts it back from the file's last '{key}'",
                           f"export with absolute indices, or put every '{key}' line above the faces")


def _locate_range(plain: str, counts: dict[str, int], path: str) -> None:
    """Raise at the first corner whose v or vt index is outside the file's vertices / texture coordinates."""
    text = "\n".join(m.group() for m in _FACE_LINE.finditer(plain))
    for key, what in (("v", "vertex"), ("vt", "texture coordinate")):
        tokens = _INDEX[key].findall(text)
        if not tokens:  # faces without texture references
            continue
        values = _index_values(tokens, _LONG_INDEX.search(text) is not None)
        bad = (values > counts[key]) | (values < -counts[key])
        if not bad.any():
            continue
        first = int(np.argmax(bad))
        written, value, digits = tokens[first], int(values[first]), len(tokens[first].lstrip("-"))
        shown = written if digits <= 20 else str(value) if abs(value) < _INDEX_CLAMP else \
            f"{written[:10]}...({digits:,} digits)"
        for face in _FACE_LINE.finditer(plain):  # its first place in the file (a same token is as bad)
            hit = next((h for h in _INDEX[key].finditer(face.group()) if h.group(1) == written), None)
            if hit:
                number, _, offset = _line_at(plain, face.start() + hit.start(1))
                problem = (f"{what} index {shown} points before the first {what}" if written.startswith("-") else
                           f"{what} index {shown} is out of range: the file has {counts[key]} "
                           f"{'vertices' if key == 'v' else what + 's'}")
                raise FdpError(path, number, offset + 1, problem, _INDEX_HINT)


_LONG_INDEX = re.compile(r"[0-9]{19}")
_INDEX_CLAMP = 10 ** 18
"""An index of 19 or more digits reads as +-10**18: past any count a file can hold (and past what int64, or
Python's ``int()`` of a string of over 4,300 digits, takes), so it is out of range whatever its value."""


def _index_values(tokens: list[str], long: bool) -> np.ndarray:
    """The int64 value of each index token (``long``: some token may have 19 digits or more, clamped)."""
    if not long:  # the common case in C: every token fits int64 (and a fixed-width array stays small)
        return np.array(tokens).astype(np.int64)
    return np.fromiter((_clamped(t) for t in tokens), np.int64, len(tokens))


def _clamped(token: str) -> int:
    digits = token.lstrip("-").lstrip("0")
    value = int(digits or "0") if len(digits) < 19 else _INDEX_CLAMP
    return -value if token.startswith("-") else value


def _locate_unbounded(plain: str, key: str, path: str) -> None:
    """Raise at the first number of a ``v`` (x y z) or ``vt`` (u v) statement that is not finite or beyond
    :data:`MAX_COORDINATE` (trimesh read it; a mesh that far out overflows the arithmetic done on it)."""
    used = 3 if key == "v" else 2
    for statement in _STATEMENT[key].finditer(plain):
        end = plain.find("\n", statement.end())
        line = plain[statement.end():end if end >= 0 else len(plain)]
        for token in list(re.finditer(r"\S+", line))[:used]:
            if not abs(float(token.group())) <= MAX_COORDINATE:
                number, _, offset = _line_at(plain, statement.end() + token.start())
                shown = token.group() if len(token.group()) <= 24 else f"{token.group()[:12]}..."
                raise FdpError(path, number, offset + 1, f"coordinate {shown} is beyond +-{MAX_COORDINATE:g}",
                               "a mesh's coordinates must be finite and within that bound: check the file's unit")
    raise FdpError.no_place(path, f"a {'vertex' if key == 'v' else 'texture coordinate'} is beyond "
                            f"+-{MAX_COORDINATE:g}", "check the file's unit")


def _line_at(text: str, position: int) -> tuple[int, str, int]:
    """(1-based line number, the line, 0-based column) of ``position`` in ``text``."""
    begin = text.rfind("\n", 0, position) + 1
    end = text.find("\n", position)
    return text.count("\n", 0, position) + 1, text[begin:end if end >= 0 else len(text)], position - begin
