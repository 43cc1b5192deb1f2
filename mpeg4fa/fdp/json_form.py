"""The human-readable FDP form: JSON that people can read, diff and edit by hand.

Schema (``version`` 1; only ``format`` and ``version`` are required)::

    {
     "format": "mpeg4fa-fdp", "version": 1, "name": "alice",
     "feature_points": {"2.1": [x, y, z], ...},          model units, any subset of the 84
     "texture_coords": {"2.1": [u, v], ...},             same labels as feature_points
     "fapu": {"IRISD0": d, "ES0": d, "ENS0": d, "MNS0": d, "MW0": d},   any subset
     "textures": [{"name": .., "media_type": "image/png", "data_base64": ".."}],
     "mesh": {"name": .., "vertices": [[x, y, z], ...], "triangles": [[a, b, c], ...],
              "uvs": [[u, v], ...]},                      uvs optional
     "face_def_tables": [{"fap": 3, "high_level_select": 1,
                          "meshes": [{"coord_index": [..], "interval_borders": [..],
                                      "displacements": [[[dx, dy, dz] per interval] per vertex]}],
                          "transforms": [{"field": "rotation", "rotation": [x, y, z, angle],
                                          "scale": [sx, sy, sz], "translation": [tx, ty, tz]}]}]
    }

Floats are written with ``repr`` precision, so a round trip is exact. Unknown
keys are errors (a typo would otherwise be dropped silently), as are duplicate
keys. Every error is an :class:`FdpError` at ``line:column``: a bad value is
reported where the value starts, a bad key (unknown, duplicate, not a feature
point label) where the key starts. A document of more than :data:`MAX_JSON_CHARS`
characters is refused before it is parsed: parsed JSON takes several times its text in memory.
"""
from __future__ import annotations

import base64
import binascii
import json
import math
import re
from json.decoder import scanstring
from typing import Any, Callable

import numpy as np

from mpeg4fa import jsonio
from mpeg4fa.fdp.errors import FdpError
from mpeg4fa.fdp.model import (FAPU_KEYS, INT32_MAX, INT32_MIN, UINT32_MAX, FaceDefMesh, FaceDefTable,
                               FaceDefTransform, Fdp, FdpMesh, FdpValueError, TextureImage, Where)
from mpeg4fa.spec import N_FAPS

FORMAT = "mpeg4fa-fdp"
VERSION = 1
MAX_JSON_CHARS = 32 << 20
"""Longest JSON document read (32 Mi characters): a textured face with a 100,000-vertex mesh takes ~20 MB."""
MAX_DEPTH = 16
"""Deepest nesting read: the schema's deepest value (a displacement in a face definition table) is 8 levels in."""

_TOP_KEYS = ("format", "version", "name", "feature_points", "texture_coords", "fapu", "textures", "mesh",
             "face_def_tables")
_MESH_KEYS = ("name", "vertices", "triangles", "uvs")
_TEXTURE_KEYS = ("name", "media_type", "data_base64")
_TABLE_KEYS = ("fap", "high_level_select", "meshes", "transforms")
_FDM_KEYS = ("coord_index", "interval_borders", "displacements")
_TRANSFORM_KEYS = ("field", "rotation", "scale", "translation")
_WS = re.compile(r"[ \t\n\r]*")
_DECODER = json.JSONDecoder()


# ---- writing ------------------------------------------------------------------------------


def fdp_to_json(fdp: Fdp) -> str:
    """The JSON form of ``fdp``: one key per line, one point / vertex / triangle per line."""
    doc: dict[str, Any] = {"format": FORMAT, "version": VERSION, "name": fdp.name,
                           "feature_points": {label: row.tolist() for label, row in zip(fdp.labels, fdp.points)}}
    if fdp.texture_coords is not None:
        doc["texture_coords"] = {label: row.tolist() for label, row in zip(fdp.labels, fdp.texture_coords)}
    if fdp.fapu is not None:
        doc["fapu"] = dict(fdp.fapu)
    if fdp.textures:
        doc["textures"] = [{"name": t.name, "media_type": t.media_type,
                            "data_base64": base64.b64encode(t.data).decode("ascii")} for t in fdp.textures]
    if fdp.mesh is not None:
        mesh: dict[str, Any] = {"name": fdp.mesh.name, "vertices": fdp.mesh.vertices.tolist(),
                                "triangles": fdp.mesh.triangles.tolist()}
        if fdp.mesh.uvs is not None:
            mesh["uvs"] = fdp.mesh.uvs.tolist()
        doc["mesh"] = mesh
    if fdp.tables:
        doc["face_def_tables"] = [_table_doc(t) for t in fdp.tables]
    return _emit(doc, 0) + "\n"


def _table_doc(table: FaceDefTable) -> dict[str, Any]:
    return {
        "fap": table.fap, "high_level_select": table.high_level_select,
        "meshes": [{"coord_index": m.coord_index.tolist(), "interval_borders": m.interval_borders.tolist(),
                    "displacements": m.displacements.tolist()} for m in table.meshes],
        "transforms": [{"field": t.field, "rotation": t.rotation.tolist(), "scale": t.scale.tolist(),
                        "translation": t.translation.tolist()} for t in table.transforms],
    }


def _emit(value: Any, depth: int) -> str:
    """JSON with containers of scalars on one line and containers of containers one item per line."""
    pad, inner = " " * depth, " " * (depth + 1)
    if isinstance(value, dict):
        if not value:
            return "{}"
        items = [f"{inner}{json.dumps(k, ensure_ascii=False)}: {_emit(v, depth + 1)}" for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(value, list):
        if not any(isinstance(v, (list, dict)) for v in value):
            return json.dumps(value, allow_nan=False, ensure_ascii=False)
        return "[\n" + ",\n".join(inner + _emit(v, depth + 1) for v in value) + "\n" + pad + "]"
    return json.dumps(value, allow_nan=False, ensure_ascii=False)


# ---- reading: locating a path in the text ---------------------------------------------------


class _Object(dict):
    """A JSON object that remembers keys given more than once (``json`` keeps only the last)."""

    duplicates: list[str]


def _pairs(pairs: list[tuple[str, Any]]) -> _Object:
    obj = _Object(pairs)
    obj.duplicates = []
    if len(obj) != len(pairs):
        seen: set[str] = set()
        for key, _ in pairs:
            if key in seen:
                obj.duplicates.append(key)
            seen.add(key)
    return obj


def _skip_ws(text: str, pos: int) -> int:
    return _WS.match(text, pos).end()  # type: ignore[union-attr]


def _offset_of(text: str, where: Where, key: bool = False) -> int:
    """Offset of the value at ``where`` (of its key, with ``key``) in valid JSON text.

    Walks the text, skipping unwanted values with the C decoder, so it costs one
    pass over the document and runs only when there is an error to report. For a
    key given more than once it finds the last one (the one ``json`` kept). Stops
    at the deepest part of the path it can find.
    """
    pos = _skip_ws(text, 0)
    for step, comp in enumerate(where):
        last = step == len(where) - 1
        if pos >= len(text):
            break
        if text[pos] == "{" and isinstance(comp, str):
            found = None
            p = _skip_ws(text, pos + 1)
            while p < len(text) and text[p] == '"':
                name, after = scanstring(text, p + 1)
                value_at = _skip_ws(text, _skip_ws(text, after) + 1)
                if name == comp:
                    found = (p, value_at)
                _, end = _DECODER.raw_decode(text, value_at)
                p = _skip_ws(text, end)
                if p < len(text) and text[p] == ",":
                    p = _skip_ws(text, p + 1)
                else:
                    break
            if found is None:
                break
            pos = found[0] if last and key else found[1]
        elif text[pos] == "[" and isinstance(comp, int) and not isinstance(comp, bool):
            p = _skip_ws(text, pos + 1)
            index = 0
            while p < len(text) and text[p] != "]" and index < comp:
                _, end = _DECODER.raw_decode(text, p)
                p = _skip_ws(text, end)
                if p < len(text) and text[p] == ",":
                    p = _skip_ws(text, p + 1)
                index += 1
            if index != comp or p >= len(text) or text[p] == "]":
                break
            pos = p
        else:
            break
    return pos


def _line_col(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


# ---- reading: checked access to the parsed document ------------------------------------------


class _Doc:
    """The parsed document plus the text, to turn a path into line:column on failure."""

    def __init__(self, text: str, path: str) -> None:
        self.text = text
        self.path = path

    def fail(self, where: Where, problem: str, hint: str = "", key: bool = False) -> FdpError:
        """An error at the value at ``where``, or at its key (for faults in the key itself)."""
        line, col = _line_col(self.text, _offset_of(self.text, where, key))
        return FdpError(self.path, line, col, problem, hint)

    def build(self, prefix: Where, make: Callable[..., Any], *args: Any, **kw: Any) -> Any:
        """``make(*args, **kw)``, with a model error reported at ``prefix + error.field``."""
        try:
            return make(*args, **kw)
        except FdpValueError as exc:
            raise self.fail(prefix + exc.field, exc.message, key=exc.key) from None

    def obj(self, value: Any, where: Where, what: str, keys: tuple[str, ...],
            required: tuple[str, ...] = ()) -> dict:
        if not isinstance(value, dict):
            raise self.fail(where, f"{what} must be a JSON object {{...}}, got {_kind(value)}")
        duplicates = getattr(value, "duplicates", [])
        if duplicates:
            raise self.fail(where + (duplicates[0],), f"key {duplicates[0]!r} given twice in {what}", key=True)
        if keys:  # empty: any key (labels)
            for key in value:
                if key not in keys:
                    raise self.fail(where + (key,), f"unknown key {key!r} in {what}", f"known: {', '.join(keys)}",
                                    key=True)
        for key in required:
            if key not in value:
                raise self.fail(where, f"{what} lacks the required key {key!r}")
        return value

    def array(self, value: Any, where: Where, what: str) -> list:
        if not isinstance(value, list):
            raise self.fail(where, f"{what} must be a JSON array [...], got {_kind(value)}")
        return value

    def string(self, value: Any, where: Where, what: str) -> str:
        if not isinstance(value, str):
            raise self.fail(where, f"{what} must be a string, got {_kind(value)}")
        return value

    def number(self, value: Any, where: Where, what: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(where, f"{what} must be a number, got {_kind(value)}")
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise self.fail(where, f"{what} must be a finite number, got {value!r}",
                            "JSON has no NaN or Infinity; numbers must fit a 64-bit float")
        return number

    def integer(self, value: Any, where: Where, what: str, lo: int, hi: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(where, f"{what} must be an integer, got {_kind(value)}")
        if not lo <= value <= hi:
            raise self.fail(where, f"{what} must lie in {lo}..{hi}, got {value}")
        return value

    def vector(self, value: Any, n: int, where: Where, what: str) -> list[float]:
        items = self.array(value, where, what)
        if len(items) != n:
            raise self.fail(where, f"{what} must have {n} numbers, got {len(items)}")
        return [self.number(v, where + (i,), what) for i, v in enumerate(items)]

    def rows(self, value: Any, n: int, where: Where, what: str) -> np.ndarray:
        rows = self.array(value, where, what)
        data = [self.vector(row, n, where + (i,), what) for i, row in enumerate(rows)]
        return np.array(data, dtype=np.float64).reshape(len(data), n)

    def integers(self, value: Any, where: Where, what: str, lo: int, hi: int, n: int = 0) -> np.ndarray:
        """Flat integer list (n == 0) or list of n-integer rows."""
        items = self.array(value, where, what)
        if not n:
            return np.array([self.integer(v, where + (i,), what, lo, hi) for i, v in enumerate(items)],
                            dtype=np.int64)
        out = []
        for i, row in enumerate(items):
            row = self.array(row, where + (i,), what)
            if len(row) != n:
                raise self.fail(where + (i,), f"{what} must have {n} integers, got {len(row)}")
            out.append([self.integer(v, where + (i, j), what, lo, hi) for j, v in enumerate(row)])
        return np.array(out, dtype=np.int64).reshape(len(out), n)


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, str):
        return f"the string {value[:40]!r}"
    return repr(value)


# ---- reading: the schema ------------------------------------------------------------------------


def fdp_from_json(text: str | bytes, path: str = "<string>") -> Fdp:
    """Parse the JSON form; any fault is an :class:`FdpError` at its line:column."""
    text = _decode(text, path)
    if len(text) > MAX_JSON_CHARS:
        raise FdpError.no_place(path, f"the JSON document has {len(text):,} characters, more than an FDP may "
                                f"({MAX_JSON_CHARS:,})", "is this an FDP file?")
    root = _parse(text, path)
    doc = _Doc(text, path)
    top = doc.obj(root, (), "the FDP document", _TOP_KEYS, required=("format", "version"))
    if top["format"] != FORMAT:
        raise doc.fail(("format",), f"format must be {FORMAT!r}, got {top['format']!r}",
                       "this file is not an mpeg4fa FDP")
    version = doc.integer(top["version"], ("version",), "version", 0, 2**63)
    if version != VERSION:
        newer = "a newer" if version > VERSION else "an unknown"
        raise doc.fail(("version",), f"FDP JSON version {version} is {newer} version; this reader knows "
                       f"version {VERSION}", "upgrade mpeg4fa" if version > VERSION else "")
    name = doc.string(top.get("name", ""), ("name",), "name")
    points = doc.obj(top.get("feature_points", {}), ("feature_points",), "feature_points", ())
    labels = tuple(points)
    coords = np.array([doc.vector(points[label], 3, ("feature_points", label), f"point {label}")
                       for label in labels], dtype=np.float64).reshape(len(labels), 3)
    return doc.build((), Fdp, labels, coords, texture_coords=_texture_coords(doc, top, labels),
                     textures=_textures(doc, top), mesh=_mesh(doc, top), tables=_tables(doc, top),
                     fapu=_fapu(doc, top), name=name)


def _decode(text: str | bytes, path: str) -> str:
    """The document as text: UTF-8 checked and located by the package's JSON reader (:mod:`mpeg4fa.jsonio`)."""
    return jsonio.json_text(text, path, FdpError, "FDP JSON")


def _parse(text: str, path: str, what: str = "an FDP document") -> Any:
    """The parsed document: nesting (at most :data:`MAX_DEPTH`), numbers and syntax checked by
    :func:`mpeg4fa.jsonio.loads`, duplicate keys remembered for the schema's checks."""
    return jsonio.loads(text, path, max_bytes=4 * MAX_JSON_CHARS, max_depth=MAX_DEPTH, error=FdpError,
                        what=what, object_pairs_hook=_pairs)


def _texture_coords(doc: _Doc, top: dict, labels: tuple[str, ...]) -> np.ndarray | None:
    if "texture_coords" not in top:
        return None
    where: Where = ("texture_coords",)
    tc = doc.obj(top["texture_coords"], where, "texture_coords", ())
    for label in tc:
        if label not in labels:
            raise doc.fail(where + (label,), f"texture coordinates for {label!r}, which has no feature point",
                           "texture_coords must use the labels of feature_points", key=True)
    for label in labels:
        if label not in tc:
            raise doc.fail(where, f"texture_coords lacks point {label}",
                           "give [u, v] for every feature point, or leave texture_coords out")
    return np.array([doc.vector(tc[label], 2, where + (label,), f"texture coordinates of {label}")
                     for label in labels], dtype=np.float64).reshape(len(labels), 2)


def _fapu(doc: _Doc, top: dict) -> dict[str, float] | None:
    if "fapu" not in top:
        return None
    fapu = doc.obj(top["fapu"], ("fapu",), "fapu", FAPU_KEYS)
    return {key: doc.number(value, ("fapu", key), f"FAPU distance {key}") for key, value in fapu.items()}


def _textures(doc: _Doc, top: dict) -> tuple[TextureImage, ...]:
    out = []
    for i, item in enumerate(doc.array(top.get("textures", []), ("textures",), "textures")):
        here: Where = ("textures", i)
        tex = doc.obj(item, here, "a texture", _TEXTURE_KEYS, required=_TEXTURE_KEYS)
        encoded = doc.string(tex["data_base64"], here + ("data_base64",), "data_base64")
        try:
            data = base64.b64decode(encoded, validate=True)
        except (binascii.Error, ValueError) as exc:
            raise doc.fail(here + ("data_base64",), f"data_base64 is not valid base64 ({exc})") from None
        out.append(doc.build(here, TextureImage, doc.string(tex["name"], here + ("name",), "name"),
                             doc.string(tex["media_type"], here + ("media_type",), "media_type"), data))
    return tuple(out)


def _mesh(doc: _Doc, top: dict) -> FdpMesh | None:
    if "mesh" not in top:
        return None
    here: Where = ("mesh",)
    mesh = doc.obj(top["mesh"], here, "mesh", _MESH_KEYS, required=("vertices", "triangles"))
    vertices = doc.rows(mesh["vertices"], 3, here + ("vertices",), "a vertex")
    triangles = doc.integers(mesh["triangles"], here + ("triangles",), "triangle vertex index", 0, UINT32_MAX, n=3)
    uvs = doc.rows(mesh["uvs"], 2, here + ("uvs",), "a uv") if "uvs" in mesh else None
    name = doc.string(mesh.get("name", ""), here + ("name",), "mesh name")
    return doc.build(here, FdpMesh, vertices, triangles, uvs, name)


def _tables(doc: _Doc, top: dict) -> tuple[FaceDefTable, ...]:
    out = []
    for i, item in enumerate(doc.array(top.get("face_def_tables", []), ("face_def_tables",), "face_def_tables")):
        here: Where = ("face_def_tables", i)
        table = doc.obj(item, here, "a face def table", _TABLE_KEYS, required=("fap",))
        fap = doc.integer(table["fap"], here + ("fap",), "fap", 1, N_FAPS)
        hls = doc.integer(table.get("high_level_select", 1), here + ("high_level_select",), "high_level_select",
                          1, 64)
        meshes = tuple(_face_def_mesh(doc, m, here + ("meshes", j))
                       for j, m in enumerate(doc.array(table.get("meshes", []), here + ("meshes",), "meshes")))
        transforms = tuple(_transform(doc, t, here + ("transforms", j)) for j, t in
                           enumerate(doc.array(table.get("transforms", []), here + ("transforms",), "transforms")))
        out.append(doc.build(here, FaceDefTable, fap, hls, meshes, transforms))
    return tuple(out)


def _face_def_mesh(doc: _Doc, value: Any, here: Where) -> FaceDefMesh:
    fdm = doc.obj(value, here, "a face def mesh", _FDM_KEYS, required=_FDM_KEYS)
    index = doc.integers(fdm["coord_index"], here + ("coord_index",), "coord_index", 0, UINT32_MAX)
    borders = doc.integers(fdm["interval_borders"], here + ("interval_borders",), "interval border",
                           INT32_MIN, INT32_MAX)
    intervals = max(len(borders) - 1, 0)
    where = here + ("displacements",)
    per_vertex = doc.array(fdm["displacements"], where, "displacements")
    if len(per_vertex) != len(index):
        raise doc.fail(where, f"displacements must have one entry per coord_index ({len(index)}), "
                       f"got {len(per_vertex)}")
    disp = np.zeros((len(index), intervals, 3))
    for i, entry in enumerate(per_vertex):
        entry = doc.array(entry, where + (i,), "displacements of a vertex")
        if len(entry) != intervals:
            raise doc.fail(where + (i,), f"a vertex needs one displacement per interval ({intervals}), "
                           f"got {len(entry)}")
        for j, vec in enumerate(entry):
            disp[i, j] = doc.vector(vec, 3, where + (i, j), "a displacement")
    return doc.build(here, FaceDefMesh, index, borders, disp)


def _transform(doc: _Doc, value: Any, here: Where) -> FaceDefTransform:
    tr = doc.obj(value, here, "a face def transform", _TRANSFORM_KEYS, required=("field",))
    kw: dict[str, Any] = {}
    for key, n in (("rotation", 4), ("scale", 3), ("translation", 3)):
        if key in tr:
            kw[key] = doc.vector(tr[key], n, here + (key,), key)
    return doc.build(here, FaceDefTransform, doc.string(tr["field"], here + ("field",), "field"), **kw)
