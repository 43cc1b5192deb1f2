"""The FDP data model: what a sender transmits so that a decoder can calibrate its own head.

An :class:`Fdp` holds any subset of the 84 feature points (model units; +x toward
the face's left, +y up, +z out of the face), optionally their texture
coordinates, texture images, a whole face mesh and per-FAP deformation tables in
the shape of the BIFS FaceDefTables / FaceDefMesh / FaceDefTransform nodes
(facts file §5.11).

Objects are immutable: constructors copy and check their inputs and store
read-only numpy arrays. A bad value raises :class:`FdpValueError`, an
:class:`~mpeg4fa.errors.MpegFaError` and ``ValueError`` that also carries ``field``, the path of the
fault in the JSON form (``("feature_points", "2.1")``, ``("mesh", "triangles", 7)``); the readers
turn that path into a line:column or byte offset. Equality compares arrays by
value, so round trips can be checked with ``==``.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields
from dataclasses import field as _default
from typing import Any, Iterable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from mpeg4fa.errors import MpegFaError
from mpeg4fa.spec import FAPU_NAMES, FEATURE_POINTS, N_FAPS

LABELS: tuple[str, ...] = tuple(fp.label for fp in FEATURE_POINTS)
"""The 84 feature point labels in the standard's (ascending) order."""
LABEL_INDEX: dict[str, int] = {label: i for i, label in enumerate(LABELS)}
FAPU_KEYS: tuple[str, ...] = FAPU_NAMES
"""Neutral-face distances a sender may give, in ``spec/fapu.csv`` order; FAPU = distance / 1024 (AU is fixed, so absent)."""
TRANSFORM_FIELDS: tuple[str, ...] = ("rotation", "scale", "translation")
MAX_HIGH_LEVEL_SELECT = 64
MAX_TEXT_BYTES = 0xFFFF
"""Longest name or media type (UTF-8 bytes): the binary form stores lengths in a u16."""
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
UINT32_MAX = 2**32 - 1
MAX_COORDINATE = 1e9
"""Largest magnitude of a mesh's coordinate (vertex position or texture coordinate) in any unit: a head is
about 0.2 m, 200 mm, 2e8 nm. Beyond it the arithmetic on a mesh (squared lengths, areas, FAPU, trimesh's
transforms, float32 for the GPU) overflows to infinity or NaN; within it, sums of squares over a million
vertices stay far inside a double. The OBJ reader, the editor's readers and the face rig
(:func:`mpeg4fa.face.custom.head_from_mesh`, which also takes an FDP's own mesh) refuse a mesh beyond it,
naming the vertex. (:class:`FdpMesh` holds any finite numbers: what a stream carries.)"""

Where = tuple[Any, ...]
_MEDIA_TYPE = re.compile(r"[A-Za-z0-9][A-Za-z0-9!#$&^_.+-]*/[A-Za-z0-9][A-Za-z0-9!#$&^_.+-]*\Z")


class FdpValueError(MpegFaError, ValueError):
    """A value the model rejects; ``field`` is its path in the JSON form (may be relative).

    ``where`` renders that path as text (``feature_points/2.1``), so ``str()`` reads
    ``feature_points/2.1: message``; the readers turn ``field`` into a line:column or byte offset.
    """

    def __init__(self, message: str, where: Where = (), key: bool = False, hint: str = "") -> None:
        self.field: Where = tuple(where)
        self.key = key
        """True when the fault is the last path element itself (a bad label), not the value under it."""
        super().__init__(message, "/".join(str(part) for part in self.field) or None, hint)

    def __reduce__(self):
        return (type(self), (self.message, self.field, self.key, self.hint))


# ---- checking helpers -----------------------------------------------------------------


def _frozen(arr: np.ndarray) -> np.ndarray:
    arr.flags.writeable = False
    return arr


def _float_array(value: ArrayLike, cols: int, what: str, where: Where) -> np.ndarray:
    """A finite (n, cols) float64 copy of ``value`` (``cols`` 0: a flat (n,) array)."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise FdpValueError(f"{what} must be an array of numbers ({exc})", where) from None
    if arr.size == 0:
        arr = arr.reshape((0, cols) if cols else (0,))
    shape_ok = arr.ndim == 1 if not cols else (arr.ndim == 2 and arr.shape[1] == cols)
    if not shape_ok:
        want = "(n,)" if not cols else f"(n, {cols})"
        raise FdpValueError(f"{what} must have shape {want}, got {arr.shape}", where)
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1) if cols else ~np.isfinite(arr))
    if bad.size:
        raise FdpValueError(f"{what} must be finite numbers", where + (int(bad[0]),))
    return _frozen(arr)


def first_unbounded(values: ArrayLike, bound: float = MAX_COORDINATE) -> int | None:
    """Index of the first row of ``values`` holding a number that is not finite or beyond +-``bound``
    (:data:`MAX_COORDINATE`), or None: the one test every mesh reader makes before its arithmetic."""
    arr = np.asarray(values, dtype=np.float64)
    bad = ~(np.abs(arr) <= bound)  # NaN compares false: caught with the infinities
    if arr.ndim > 1:
        bad = bad.any(axis=tuple(range(1, arr.ndim)))
    hits = np.flatnonzero(bad)
    return int(hits[0]) if hits.size else None


def _int_array(value: ArrayLike, what: str, where: Where, lo: int, hi: int, cols: int = 0) -> np.ndarray:
    """An int64 copy of ``value`` whose entries lie in [lo, hi]; shape (n,) or (n, cols)."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise FdpValueError(f"{what} must be an array of integers ({exc})", where) from None
    if raw.size == 0:
        raw = np.zeros((0, cols) if cols else (0,), dtype=np.int64)
    if raw.dtype.kind not in "iu":
        raise FdpValueError(f"{what} must hold integers, got {raw.dtype}", where)
    shape_ok = raw.ndim == 1 if not cols else (raw.ndim == 2 and raw.shape[1] == cols)
    if not shape_ok:
        want = "(n,)" if not cols else f"(n, {cols})"
        raise FdpValueError(f"{what} must have shape {want}, got {raw.shape}", where)
    outside = (raw < lo) | (raw > hi)
    if outside.any():
        first = np.argwhere(outside)[0]
        row = int(first[0])
        raise FdpValueError(f"{what} must lie in [{lo}, {hi}], got {int(raw[tuple(first)])}", where + (row,))
    return _frozen(raw.astype(np.int64))


def _vector(value: ArrayLike, n: int, what: str, where: Where) -> np.ndarray:
    """A finite (n,) float64 copy of ``value``."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise FdpValueError(f"{what} must be {n} numbers", where) from None
    if arr.shape != (n,):
        raise FdpValueError(f"{what} must be {n} numbers, got shape {arr.shape}", where)
    if not np.isfinite(arr).all():
        raise FdpValueError(f"{what} must be finite numbers", where)
    return _frozen(arr)


def _text(value: Any, what: str, where: Where) -> str:
    if not isinstance(value, str):
        raise FdpValueError(f"{what} must be a string, got {type(value).__name__}", where)
    try:
        size = len(value.encode("utf-8"))
    except UnicodeEncodeError:
        raise FdpValueError(f"{what} is not valid Unicode text (lone surrogate)", where) from None
    if size > MAX_TEXT_BYTES:
        raise FdpValueError(f"{what} is {size} bytes long; at most {MAX_TEXT_BYTES} UTF-8 bytes", where)
    return value


def _integer(value: Any, what: str, lo: int, hi: int, where: Where) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise FdpValueError(f"{what} must be an integer, got {value!r}", where)
    if not lo <= int(value) <= hi:
        raise FdpValueError(f"{what} must lie in {lo}..{hi}, got {int(value)}", where)
    return int(value)


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.shape == b.shape
                and bool(np.array_equal(a, b)))
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return bool(a == b)


class _ValueEquality:
    """``==`` field by field, arrays by value; objects holding arrays are not hashable."""

    __hash__ = None  # type: ignore[assignment]

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, f.name), getattr(other, f.name)) for f in fields(self))  # type: ignore[arg-type]


def _set(obj: object, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


# ---- the parts --------------------------------------------------------------------------


@dataclass(frozen=True)
class TextureImage:
    """One texture image, kept as the encoded file bytes (PNG, JPEG...) so nothing is re-encoded."""

    name: str
    media_type: str
    """IANA media type, e.g. ``"image/png"``."""
    data: bytes

    def __post_init__(self) -> None:
        _text(self.name, "texture name", ("name",))
        _text(self.media_type, "media type", ("media_type",))
        if not _MEDIA_TYPE.match(self.media_type):
            raise FdpValueError(f"media type {self.media_type!r} is not of the form type/subtype "
                                "(e.g. image/png)", ("media_type",))
        if not isinstance(self.data, (bytes, bytearray, memoryview)):
            raise FdpValueError(f"texture data must be bytes, got {type(self.data).__name__}", ("data_base64",))
        _set(self, "data", bytes(self.data))

    def __repr__(self) -> str:
        return f"TextureImage(name={self.name!r}, media_type={self.media_type!r}, {len(self.data)} bytes)"


@dataclass(frozen=True, eq=False)
class FdpMesh(_ValueEquality):
    """A whole face model sent with the FDP (BIFS ``faceSceneGraph``, reduced to one triangle mesh)."""

    vertices: np.ndarray
    """(V, 3) float64, model units, same axes as the feature points."""
    triangles: np.ndarray
    """(T, 3) int64 vertex indices, counter-clockwise seen from outside."""
    uvs: np.ndarray | None = None
    """(V, 2) texture coordinates per vertex, or None."""
    name: str = ""

    def __post_init__(self) -> None:
        verts = _float_array(self.vertices, 3, "mesh vertices", ("vertices",))
        n = len(verts)
        tris = _int_array(self.triangles, "triangle vertex indices", ("triangles",), 0, max(n - 1, 0), cols=3)
        if n == 0 and len(tris):
            raise FdpValueError("triangles refer to vertices but the mesh has none", ("triangles", 0))
        uvs = None
        if self.uvs is not None:
            uvs = _float_array(self.uvs, 2, "mesh uvs", ("uvs",))
            if len(uvs) != n:
                raise FdpValueError(f"mesh has {n} vertices but {len(uvs)} uvs", ("uvs",))
        _set(self, "vertices", verts)
        _set(self, "triangles", tris)
        _set(self, "uvs", uvs)
        _text(self.name, "mesh name", ("name",))

    def __repr__(self) -> str:
        uv = ", uvs" if self.uvs is not None else ""
        return f"FdpMesh(name={self.name!r}, {len(self.vertices)} vertices, {len(self.triangles)} triangles{uv})"


@dataclass(frozen=True, eq=False)
class FaceDefMesh(_ValueEquality):
    """Piecewise-linear vertex displacements driven by one FAP (BIFS FaceDefMesh).

    ``interval_borders`` b0 < b1 < ... < bm split the FAP value axis (in FAPU)
    into m intervals; ``displacements[i, j]`` is the displacement of vertex
    ``coord_index[i]`` per FAP unit inside interval j.
    """

    coord_index: np.ndarray
    """(k,) int64 indices into the FDP's mesh vertices."""
    interval_borders: np.ndarray
    """(m+1,) int64, strictly increasing, m >= 1 (BIFS MFInt32, so within int32)."""
    displacements: np.ndarray
    """(k, m, 3) float64: one displacement per vertex per interval."""

    def __post_init__(self) -> None:
        index = _int_array(self.coord_index, "coord_index", ("coord_index",), 0, UINT32_MAX)
        borders = _int_array(self.interval_borders, "interval_borders", ("interval_borders",), INT32_MIN, INT32_MAX)
        if len(borders) < 2:
            raise FdpValueError("interval_borders needs at least 2 values (one interval)", ("interval_borders",))
        steps = np.flatnonzero(np.diff(borders) <= 0)
        if steps.size:
            raise FdpValueError("interval_borders must be strictly increasing",
                                ("interval_borders", int(steps[0]) + 1))
        k, m = len(index), len(borders) - 1
        try:
            disp = np.array(self.displacements, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise FdpValueError(f"displacements must be an array of numbers ({exc})", ("displacements",)) from None
        if disp.size == 0 and k == 0:
            disp = disp.reshape(0, m, 3)
        if disp.shape != (k, m, 3):
            raise FdpValueError(f"displacements must have shape (k, m, 3) = ({k}, {m}, 3) for {k} vertices and "
                                f"{m} intervals, got {disp.shape}", ("displacements",))
        bad = np.flatnonzero(~np.isfinite(disp).all(axis=(1, 2)))
        if bad.size:
            raise FdpValueError("displacements must be finite numbers", ("displacements", int(bad[0])))
        _set(self, "coord_index", index)
        _set(self, "interval_borders", borders)
        _set(self, "displacements", _frozen(disp))

    def weights(self, fap_value: float) -> np.ndarray:
        """(m,) signed length of [0, v] inside each interval, v and 0 clamped to [b0, bm]."""
        b = self.interval_borders.astype(np.float64)
        v = min(max(float(fap_value), b[0]), b[-1])
        zero = min(max(0.0, b[0]), b[-1])
        lo, hi = b[:-1], b[1:]
        return np.clip(v, lo, hi) - np.clip(zero, lo, hi)

    def displace(self, fap_value: float) -> np.ndarray:
        """(k, 3) displacement of the listed vertices for FAP value ``fap_value`` (in FAPU).

        The displacement is the integral from 0 to v of the per-interval slope
        ``displacements[:, j]``: each interval contributes its vector times the
        signed portion of [0, v] inside it. Values beyond the outermost borders
        are clamped to them (the motion stops; it is not extrapolated). When 0 is
        outside [b0, bm] it is clamped too, so the displacement is measured from
        the nearest border and is still zero at v = 0.
        """
        if not math.isfinite(float(fap_value)):
            raise FdpValueError(f"FAP value must be finite, got {fap_value!r}")
        return np.einsum("kmc,m->kc", self.displacements, self.weights(fap_value))


@dataclass(frozen=True, eq=False)
class FaceDefTransform(_ValueEquality):
    """A rigid/scale change driven by one FAP (BIFS FaceDefTransform).

    ``field`` names the Transform field the FAP drives; only that field's
    ``*Def`` value is used. Unlike BIFS it names no target node: the transform
    applies to the FDP's mesh as a whole.
    """

    field: str = "rotation"
    rotation: np.ndarray = _default(default_factory=lambda: np.array([0.0, 0.0, 1.0, 0.0]))
    """(4,) axis x, y, z and angle in radians per FAP unit (SFRotation order)."""
    scale: np.ndarray = _default(default_factory=lambda: np.ones(3))
    """(3,) scale factors at FAP value 1."""
    translation: np.ndarray = _default(default_factory=lambda: np.zeros(3))
    """(3,) translation per FAP unit, model units."""

    def __post_init__(self) -> None:
        if self.field not in TRANSFORM_FIELDS:
            raise FdpValueError(f"transform field must be one of {', '.join(TRANSFORM_FIELDS)}, got {self.field!r}",
                                ("field",))
        rotation = _vector(self.rotation, 4, "rotation", ("rotation",))
        if not np.any(rotation[:3]):
            raise FdpValueError("rotation axis must not be the zero vector", ("rotation",))
        _set(self, "rotation", rotation)
        _set(self, "scale", _vector(self.scale, 3, "scale", ("scale",)))
        _set(self, "translation", _vector(self.translation, 3, "translation", ("translation",)))

    def at(self, fap_value: float) -> "FaceDefTransform":
        """The transform at FAP value ``fap_value``: the driven field scaled, the others identity.

        Our reading of BIFS (facts file §5.11, [M]): translation * v, rotation
        angle * v about the same axis, scale 1 + (scale - 1) * v, so that v = 0
        is always the identity and v = 1 gives the ``*Def`` values.
        """
        v = float(fap_value)
        if not math.isfinite(v):
            raise FdpValueError(f"FAP value must be finite, got {fap_value!r}")
        identity = FaceDefTransform(self.field)
        if self.field == "rotation":
            return FaceDefTransform(self.field, rotation=np.append(self.rotation[:3], self.rotation[3] * v))
        if self.field == "scale":
            return FaceDefTransform(self.field, scale=1.0 + (self.scale - 1.0) * v)
        if self.field == "translation":
            return FaceDefTransform(self.field, translation=self.translation * v)
        return identity  # pragma: no cover - field is checked in __post_init__


@dataclass(frozen=True, eq=False)
class FaceDefTable(_ValueEquality):
    """How one FAP deforms the sent mesh (BIFS FaceDefTables)."""

    fap: int
    """FAP number 1..68."""
    high_level_select: int = 1
    """For FAP 1/2: which viseme/expression this table defines (1..64); 1 otherwise."""
    meshes: tuple[FaceDefMesh, ...] = ()
    transforms: tuple[FaceDefTransform, ...] = ()

    def __post_init__(self) -> None:
        _integer(self.fap, "fap", 1, N_FAPS, ("fap",))
        _integer(self.high_level_select, "high_level_select", 1, MAX_HIGH_LEVEL_SELECT, ("high_level_select",))
        _set(self, "fap", int(self.fap))
        _set(self, "high_level_select", int(self.high_level_select))
        for name, kind in (("meshes", FaceDefMesh), ("transforms", FaceDefTransform)):
            items = tuple(getattr(self, name))
            for i, item in enumerate(items):
                if not isinstance(item, kind):
                    raise FdpValueError(f"{name} must hold {kind.__name__} objects, got {type(item).__name__}",
                                        (name, i))
            _set(self, name, items)


# ---- the whole FDP ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Fdp(_ValueEquality):
    """Face definition parameters: the data that lets a decoder calibrate its own head.

    Labels are kept in the standard's order (the constructor reorders them and
    the rows of ``points`` and ``texture_coords`` with them), without
    duplicates.
    """

    labels: tuple[str, ...]
    points: np.ndarray
    """(n, 3) float64 model units; +x toward the face's left, +y up, +z out of the face."""
    texture_coords: np.ndarray | None = None
    """(n, 2) u, v in [0, 1], one per point, or None."""
    textures: tuple[TextureImage, ...] = ()
    mesh: FdpMesh | None = None
    tables: tuple[FaceDefTable, ...] = ()
    fapu: dict[str, float] | None = None
    """Sender-side neutral distances (keys from :data:`FAPU_KEYS`, model units), or None."""
    name: str = ""

    def __post_init__(self) -> None:
        labels = self._check_labels()
        try:
            points = _float_array(self.points, 3, "feature point coordinates", ("feature_points",))
        except FdpValueError as exc:
            raise self._label_path(exc, labels) from None
        if len(points) != len(labels):
            raise FdpValueError(f"{len(labels)} labels but {len(points)} points", ("feature_points",))
        order = sorted(range(len(labels)), key=lambda i: LABEL_INDEX[labels[i]])
        _set(self, "labels", tuple(labels[i] for i in order))
        _set(self, "points", _frozen(points[order]))
        _set(self, "texture_coords", self._check_texture_coords(labels, order))
        self._check_parts()
        _set(self, "fapu", self._check_fapu())
        _text(self.name, "name", ("name",))

    def _check_labels(self) -> list[str]:
        if isinstance(self.labels, str):
            raise FdpValueError("labels must be a sequence of labels, not one string", ("feature_points",))
        labels = list(self.labels)
        seen: set[str] = set()
        for label in labels:
            if not isinstance(label, str) or label not in LABEL_INDEX:
                raise FdpValueError(f"unknown feature point label {label!r}; labels are 2.1 .. 11.6 "
                                    "(groups 2-11 of the standard)", ("feature_points", str(label)), key=True)
            if label in seen:
                raise FdpValueError(f"feature point {label} given twice", ("feature_points", label), key=True)
            seen.add(label)
        return labels

    def _check_texture_coords(self, labels: list[str], order: list[int]) -> np.ndarray | None:
        if self.texture_coords is None:
            return None
        try:
            tc = _float_array(self.texture_coords, 2, "texture coordinates", ("texture_coords",))
        except FdpValueError as exc:
            raise self._label_path(exc, labels) from None
        if len(tc) != len(labels):
            raise FdpValueError(f"{len(labels)} feature points but {len(tc)} texture coordinates",
                                ("texture_coords",))
        outside = np.flatnonzero(((tc < 0.0) | (tc > 1.0)).any(axis=1))
        if outside.size:
            label = labels[int(outside[0])]
            raise FdpValueError(f"texture coordinates of {label} must lie in [0, 1], got "
                                f"{tc[outside[0]].tolist()}", ("texture_coords", label))
        return _frozen(tc[order])

    @staticmethod
    def _label_path(exc: FdpValueError, labels: list[str]) -> FdpValueError:
        """Turn a row index in an error path into the row's label."""
        if len(exc.field) >= 2 and isinstance(exc.field[1], int) and exc.field[1] < len(labels):
            field = (exc.field[0], labels[exc.field[1]]) + exc.field[2:]
            return FdpValueError(exc.message, field, exc.key, exc.hint)
        return exc

    def _check_parts(self) -> None:
        textures = tuple(self.textures)
        for i, tex in enumerate(textures):
            if not isinstance(tex, TextureImage):
                raise FdpValueError(f"textures must hold TextureImage objects, got {type(tex).__name__}",
                                    ("textures", i))
        _set(self, "textures", textures)
        if self.mesh is not None and not isinstance(self.mesh, FdpMesh):
            raise FdpValueError(f"mesh must be an FdpMesh, got {type(self.mesh).__name__}", ("mesh",))
        tables = tuple(self.tables)
        seen: dict[tuple[int, int], int] = {}
        n_vertices = len(self.mesh.vertices) if self.mesh is not None else 0
        for i, table in enumerate(tables):
            if not isinstance(table, FaceDefTable):
                raise FdpValueError(f"tables must hold FaceDefTable objects, got {type(table).__name__}",
                                    ("face_def_tables", i))
            key = (table.fap, table.high_level_select)
            if key in seen:
                raise FdpValueError(f"FAP {table.fap} (high_level_select {table.high_level_select}) already has a "
                                    f"table (number {seen[key]})", ("face_def_tables", i, "fap"))
            seen[key] = i
            for j, fdm in enumerate(table.meshes):
                here = ("face_def_tables", i, "meshes", j)
                if self.mesh is None:
                    raise FdpValueError("a FaceDefMesh needs the FDP's mesh, and there is none", here)
                beyond = np.flatnonzero(fdm.coord_index >= n_vertices)
                if beyond.size:
                    raise FdpValueError(f"coord_index {int(fdm.coord_index[beyond[0]])} is beyond the mesh's "
                                        f"{n_vertices} vertices", here + ("coord_index", int(beyond[0])))
        _set(self, "tables", tables)

    def _check_fapu(self) -> dict[str, float] | None:
        if self.fapu is None:
            return None
        if not isinstance(self.fapu, Mapping):
            raise FdpValueError(f"fapu must be a mapping, got {type(self.fapu).__name__}", ("fapu",))
        for key in self.fapu:
            if key not in FAPU_KEYS:
                raise FdpValueError(f"unknown FAPU distance {key!r}; known: {', '.join(FAPU_KEYS)}", ("fapu", key),
                                    key=True)
        result = {}
        for key in FAPU_KEYS:
            if key in self.fapu:
                value = self.fapu[key]
                if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                    raise FdpValueError(f"FAPU distance {key} must be a number, got {value!r}", ("fapu", key))
                if not (math.isfinite(value) and value > 0):
                    raise FdpValueError(f"FAPU distance {key} must be a positive finite number, got {value!r}",
                                        ("fapu", key))
                result[key] = float(value)
        return result

    # ---- convenience ------------------------------------------------------------------

    @classmethod
    def from_points(cls, points: Mapping[str, ArrayLike], texture_coords: Mapping[str, ArrayLike] | None = None,
                    **kw: Any) -> "Fdp":
        """An Fdp from ``{label: (x, y, z)}`` (and optionally ``{label: (u, v)}`` for the same labels)."""
        labels = tuple(points)
        rows = [points[label] for label in labels]
        coords = np.array(rows, dtype=np.float64) if rows else np.zeros((0, 3))
        tc = None
        if texture_coords is not None:
            if set(texture_coords) != set(labels):
                missing = sorted(set(labels) ^ set(texture_coords), key=lambda s: LABEL_INDEX.get(s, 999))
                raise FdpValueError(f"texture_coords must cover the same labels as points; differ on {missing}",
                                    ("texture_coords",))
            tc = np.array([texture_coords[label] for label in labels], dtype=np.float64) if labels else np.zeros((0, 2))
        return cls(labels, coords, texture_coords=tc, **kw)

    def index(self, label: str) -> int:
        """Row of ``label`` in :attr:`points`; KeyError naming it when absent."""
        try:
            return self.labels.index(label)
        except ValueError:
            known = "a standard label" if label in LABEL_INDEX else "not a feature point label"
            raise KeyError(f"feature point {label!r} is not in this FDP ({known})") from None

    def point(self, label: str) -> np.ndarray:
        """(3,) coordinates of one feature point (read-only)."""
        return self.points[self.index(label)]

    def as_dict(self) -> dict[str, np.ndarray]:
        """``{label: (3,) coordinates}`` in standard order."""
        return {label: self.points[i] for i, label in enumerate(self.labels)}

    def subset(self, labels: Iterable[str]) -> "Fdp":
        """The same FDP with only the given feature points (everything else kept)."""
        rows = sorted({self.index(label) for label in labels})
        tc = None if self.texture_coords is None else self.texture_coords[rows]
        return Fdp(tuple(self.labels[i] for i in rows), self.points[rows], texture_coords=tc,
                   textures=self.textures, mesh=self.mesh, tables=self.tables, fapu=self.fapu, name=self.name)

    def head_height(self) -> float:
        """Extent of the feature points along y (max - min), a scale for tolerances."""
        if not len(self.points):
            raise FdpValueError("an FDP without feature points has no head height", ("feature_points",))
        return float(self.points[:, 1].max() - self.points[:, 1].min())

    def __repr__(self) -> str:
        parts = [f"name={self.name!r}", f"{len(self.labels)} points"]
        if self.texture_coords is not None:
            parts.append("texture coords")
        if self.textures:
            parts.append(f"{len(self.textures)} textures")
        if self.mesh is not None:
            parts.append(repr(self.mesh))
        if self.tables:
            parts.append(f"{len(self.tables)} tables")
        if self.fapu is not None:
            parts.append(f"fapu={self.fapu}")
        return f"Fdp({', '.join(parts)})"
