"""Xface's ``.fdp`` XML (facts file §6.2): which mesh vertex is each feature point.

An Xface file names vertices, not coordinates::

    <xfdp>
      <head> <file version="0.2"/> <fapu ENS0=".." ES0=".." IRISD0=".." MNS0=".." MW0=".."/>
             <translation x y z/> <rotation axis_angle axis_x axis_y axis_z/> </head>
      <source> <entity alias category> <mesh file format/> </entity> ... </source>
      <fdp affects="<submesh>" index="<vertex>" name="<label>">
        <indices>vertices it moves</indices>
        <influence fap="<0-based FAP index>" type="RaisedCosInfluenceSph" weight="0.3"/>
      </fdp> ...
    </xfdp>

so :func:`read_xface_fdp` returns an :class:`XfaceFdp` and
:meth:`XfaceFdp.to_fdp` turns it into an :class:`Fdp` once the caller supplies
the vertices of the submeshes. FAP indices are 0-based in the file and 1-based
here. A label may have several ``<fdp>`` elements, one per submesh a FAP moves
(Xface's alice gives 2.1 on the skin and on the lower teeth): the first one in
the file is the feature point itself, the rest are kept in ``entries``.

The parser is expat with DTDs refused (no entity expansion) and at most
:data:`MAX_ELEMENTS` elements (a real file has a few thousand; each element is a
Python object, so a file of nothing but ``<a/>`` must not fill memory); every fault
is an :class:`FdpError` at the line:column of the element, attribute value or token.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import Mapping, NamedTuple
from xml.parsers import expat

import numpy as np
from numpy.typing import ArrayLike

from mpeg4fa.fdp.errors import FdpError, read_bytes
from mpeg4fa.fdp.model import FAPU_KEYS, LABEL_INDEX, Fdp, FdpValueError
from mpeg4fa.spec import N_FAPS

MAX_ELEMENTS = 200_000
"""Most XML elements read; Xface's alice has about 1,000."""
_INT = re.compile(r"[+-]?[0-9]{1,18}\Z")
_FLOAT = re.compile(r"\s*[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\s*\Z")


class XfaceInfluence(NamedTuple):
    """One ``<influence>``: how FAP ``fap`` (1-based) moves the vertices of its entry."""

    fap: int
    type: str
    weight: float


@dataclass(frozen=True, eq=False)
class XfaceEntry:
    """One ``<fdp>`` element, with its place in the file for error messages."""

    label: str
    submesh: str
    """The ``affects`` attribute: name of the submesh the vertex belongs to."""
    index: int
    """The feature point's vertex in that submesh."""
    indices: np.ndarray
    """(k,) int64 vertices of the submesh that the entry's FAPs move."""
    influences: tuple[XfaceInfluence, ...]
    line: int
    column: int


@dataclass(eq=False)
class XfaceFdp:
    """The content of an Xface ``.fdp`` file.

    ``points``, ``influences`` and ``indices`` (keyed by label, in standard
    order) describe each label's first, primary ``<fdp>`` element; ``entries``
    holds every element in file order, the extra ones on other submeshes too.
    """

    version: str
    fapu: dict[str, float]
    translation: np.ndarray
    """(3,) the head's global translation (Xface display transform; not applied by :meth:`to_fdp`)."""
    rotation: np.ndarray
    """(4,) axis x, y, z and angle in radians (SFRotation order)."""
    entries: tuple[XfaceEntry, ...]
    meshes: list[tuple[str, str]]
    """``(alias, file)`` of each ``<entity>`` of ``<source>``."""
    path: str = "<string>"
    points: dict[str, tuple[str, int]] = field(init=False)
    influences: dict[str, list[tuple[int, str, float]]] = field(init=False)
    indices: dict[str, np.ndarray] = field(init=False)

    def __post_init__(self) -> None:
        primary: dict[str, XfaceEntry] = {}
        for entry in self.entries:
            primary.setdefault(entry.label, entry)
        ordered = sorted(primary.values(), key=lambda e: LABEL_INDEX[e.label])
        self.points = {e.label: (e.submesh, e.index) for e in ordered}
        self.influences = {e.label: [tuple(i) for i in e.influences] for e in ordered}  # type: ignore[misc]
        self.indices = {e.label: e.indices for e in ordered}

    def to_fdp(self, vertices_by_submesh: Mapping[str, ArrayLike], name: str = "") -> Fdp:
        """The FDP whose feature points are the primary entries' vertices, with the file's FAPU.

        ``vertices_by_submesh`` maps a submesh name (the ``affects`` attribute)
        to its (V, 3) vertices. Coordinates are taken as they are, in the mesh's
        frame; the head translation/rotation of ``<head>`` are not applied.
        """
        arrays: dict[str, np.ndarray] = {}
        for key, value in vertices_by_submesh.items():
            arr = np.asarray(value, dtype=np.float64)
            if arr.ndim != 2 or arr.shape[1] != 3:
                raise FdpValueError(f"vertices of submesh {key!r} must have shape (V, 3), got {arr.shape}",
                                    ("vertices", key))
            arrays[key] = arr
        coords: dict[str, np.ndarray] = {}
        for label, (submesh, index) in self.points.items():
            entry = next(e for e in self.entries if e.label == label)
            if submesh not in arrays:
                given = ", ".join(sorted(arrays)) or "none"
                raise FdpError(self.path, entry.line, entry.column, f"feature point {label} is on submesh "
                               f"{submesh!r}, whose vertices were not given", f"given: {given}")
            if index >= len(arrays[submesh]):
                raise FdpError(self.path, entry.line, entry.column, f"feature point {label} is vertex {index} of "
                               f"submesh {submesh!r}, which has {len(arrays[submesh])} vertices",
                               "is this the mesh the .fdp was made for?")
            coords[label] = arrays[submesh][index]
        try:
            return Fdp.from_points(coords, fapu=dict(self.fapu) or None, name=name)
        except FdpValueError as exc:
            label = exc.field[1] if len(exc.field) > 1 and exc.field[0] == "feature_points" else None
            entry = next((e for e in self.entries if e.label == label), None)
            if entry is None:
                raise
            raise FdpError(self.path, entry.line, entry.column, f"feature point {label}: {exc.message}") from None


# ---- parsing ------------------------------------------------------------------------------------


class _Node:
    __slots__ = ("tag", "attrs", "children", "text", "line", "column", "byte")

    def __init__(self, tag: str, attrs: dict[str, str], line: int, column: int, byte: int) -> None:
        self.tag, self.attrs, self.line, self.column, self.byte = tag, attrs, line, column, byte
        self.children: list[_Node] = []
        self.text: list[str] = []


class _Source:
    """The raw bytes, to place errors at an attribute value or a token inside an element."""

    def __init__(self, data: bytes, path: str) -> None:
        self.data, self.path = data, path

    def at_node(self, node: _Node, problem: str, hint: str = "") -> FdpError:
        return FdpError(self.path, node.line, node.column, problem, hint)

    def at_byte(self, offset: int, problem: str, hint: str = "") -> FdpError:
        line = self.data.count(b"\n", 0, offset) + 1
        start = self.data.rfind(b"\n", 0, offset) + 1
        column = len(self.data[start:offset].decode("utf-8", "replace")) + 1
        return FdpError(self.path, line, column, problem, hint)

    def at_attr(self, node: _Node, name: str, problem: str, hint: str = "") -> FdpError:
        end = self.data.find(b">", node.byte)
        found = re.compile(rb"\s" + re.escape(name.encode()) + rb"\s*=\s*[\"']").search(
            self.data, node.byte, end if end >= 0 else len(self.data))
        return self.at_byte(found.end(), problem, hint) if found else self.at_node(node, problem, hint)

    def at_token(self, node: _Node, token: str, problem: str, hint: str = "") -> FdpError:
        start = self.data.find(b">", node.byte) + 1
        found = re.compile(rb"(?<![^\s>])" + re.escape(token.encode("utf-8", "replace")) + rb"(?![^\s<])").search(
            self.data, start) if start > 0 else None
        return self.at_byte(found.start(), problem, hint) if found else self.at_node(node, problem, hint)


def _parse_tree(data: bytes, path: str, override_utf8: bool) -> _Node:
    parser = expat.ParserCreate(encoding="UTF-8" if override_utf8 else None)
    parser.buffer_text = True
    stack: list[_Node] = []
    roots: list[_Node] = []

    count = 0

    def start(tag: str, attrs: dict[str, str]) -> None:
        nonlocal count
        count += 1
        if count > MAX_ELEMENTS:
            raise FdpError(path, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1,
                           f"more than {MAX_ELEMENTS:,} XML elements", "an Xface .fdp has a few thousand; is this one?")
        node = _Node(tag, attrs, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, parser.CurrentByteIndex)
        (stack[-1].children if stack else roots).append(node)
        stack.append(node)

    def end(tag: str) -> None:
        stack.pop()

    def text(chars: str) -> None:
        if stack:
            stack[-1].text.append(chars)

    def refuse(*args: object) -> None:
        raise FdpError(path, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1,
                       "DTDs and entity declarations are not accepted in an Xface .fdp",
                       "remove the <!DOCTYPE ...> declaration")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        raise FdpError(path, exc.lineno, exc.offset + 1, f"invalid XML: {expat.ErrorString(exc.code)}") from None
    except FdpError:
        raise
    except (LookupError, ValueError) as exc:  # expat asks Python's codecs for a declared encoding it lacks
        raise _encoding_error(data, path, exc) from None
    return roots[0]


_ENCODING = re.compile(rb"""<\?xml[^>]*?\sencoding\s*=\s*["']([^"']*)""")


def _encoding_error(data: bytes, path: str, exc: Exception) -> FdpError:
    """The declared encoding cannot be decoded (unknown, multi-byte or not a text codec): said at its name."""
    head = data.lstrip(b"\xef\xbb\xbf \t\r\n")
    found = _ENCODING.match(head)
    hint = "save the file as UTF-8 and declare encoding=\"UTF-8\""
    if found is None:
        return FdpError(path, 1, 1, f"cannot decode the file's text ({exc})", hint)
    offset = len(data) - len(head) + found.start(1)
    name = found.group(1).decode("ascii", "replace")
    return _Source(data, path).at_byte(offset, f"unknown or unsupported XML encoding {name!r} ({exc})", hint)


def _attr(src: _Source, node: _Node, name: str) -> str:
    if name not in node.attrs:
        raise src.at_node(node, f"<{node.tag}> lacks the attribute {name}=")
    return node.attrs[name]


def _number(src: _Source, node: _Node, name: str, default: float | None = None) -> float:
    if name not in node.attrs and default is not None:
        return default
    text = _attr(src, node, name)
    value = float(text) if _FLOAT.match(text) else math.nan
    if not math.isfinite(value):
        raise src.at_attr(node, name, f"{name}= of <{node.tag}> must be a number, got {text!r}")
    return value


def _integer(src: _Source, node: _Node, name: str, lo: int, hi: int) -> int:
    text = _attr(src, node, name).strip()
    if not _INT.match(text) or not lo <= int(text) <= hi:
        raise src.at_attr(node, name, f"{name}= of <{node.tag}> must be an integer in {lo}..{hi}, got {text!r}")
    return int(text)


def _children(node: _Node, tag: str) -> list[_Node]:
    return [child for child in node.children if child.tag == tag]


def xface_from_xml(data: str | bytes, path: str = "<string>") -> XfaceFdp:
    """Parse the text of an Xface ``.fdp`` file (bytes keep the file's declared encoding)."""
    override = isinstance(data, str)
    raw = data.encode("utf-8", "surrogatepass") if isinstance(data, str) else bytes(data)
    src = _Source(raw, path)
    root = _parse_tree(raw, path, override)
    if root.tag != "xfdp":
        raise src.at_node(root, f"root element is <{root.tag}>, expected <xfdp>", "this is not an Xface .fdp file")
    version, fapu = "", {}
    translation, rotation = np.zeros(3), np.array([0.0, 0.0, 1.0, 0.0])
    for head in _children(root, "head")[:1]:
        for node in _children(head, "file")[:1]:
            version = node.attrs.get("version", "")
        for node in _children(head, "fapu")[:1]:
            for key in FAPU_KEYS:
                if key in node.attrs:
                    fapu[key] = _number(src, node, key)
                    if fapu[key] <= 0:
                        raise src.at_attr(node, key, f"FAPU distance {key} must be positive, got {fapu[key]}")
        for node in _children(head, "translation")[:1]:
            translation = np.array([_number(src, node, axis, 0.0) for axis in "xyz"])
        for node in _children(head, "rotation")[:1]:
            rotation = np.array([_number(src, node, key, default) for key, default in
                                 (("axis_x", 0.0), ("axis_y", 0.0), ("axis_z", 1.0), ("axis_angle", 0.0))])
    meshes = []
    for source in _children(root, "source"):
        for entity in _children(source, "entity"):
            alias = _attr(src, entity, "alias")
            meshes += [(alias, _attr(src, mesh, "file")) for mesh in _children(entity, "mesh")]
    entries = tuple(_entries(src, root))
    return XfaceFdp(version, fapu, translation, rotation, entries, meshes, path)


def _entries(src: _Source, root: _Node) -> list[XfaceEntry]:
    seen: dict[tuple[str, str], _Node] = {}
    out = []
    for node in _children(root, "fdp"):
        label = _attr(src, node, "name").strip()
        if label not in LABEL_INDEX:
            raise src.at_attr(node, "name", f"unknown feature point label {label!r}",
                              "labels are 2.1 .. 11.6 (groups 2-11 of the standard)")
        submesh = _attr(src, node, "affects")
        if (label, submesh) in seen:
            first = seen[(label, submesh)]
            raise src.at_node(node, f"second <fdp> for {label} on submesh {submesh!r} (the first is on line "
                              f"{first.line})")
        seen[(label, submesh)] = node
        index = _integer(src, node, "index", 0, 2**32 - 1)
        vertices: list[int] = []
        for ind in _children(node, "indices"):
            for token in "".join(ind.text).split():
                if not _INT.match(token) or int(token) < 0:
                    raise src.at_token(ind, token, f"vertex index must be a non-negative integer, got {token!r}")
                vertices.append(int(token))
        influences = []
        for inf in _children(node, "influence"):
            fap = _integer(src, inf, "fap", 0, N_FAPS - 1) + 1
            kind = _attr(src, inf, "type")
            influences.append(XfaceInfluence(fap, kind, _number(src, inf, "weight")))
        out.append(XfaceEntry(label, submesh, index, np.array(vertices, dtype=np.int64), tuple(influences),
                              node.line, node.column))
    return out


def read_xface_fdp(path: str | os.PathLike[str]) -> XfaceFdp:
    """Read an Xface ``.fdp`` file; pair with :meth:`XfaceFdp.to_fdp` and the model's vertices."""
    data = read_bytes(path)
    return xface_from_xml(data, str(path))
