"""The compact binary FDP stream (``.fdp``), specified byte by byte in ``spec/FDP_STREAM.md``.

A PNG-style container: an 8-byte magic that catches text-mode mangling, a
major/minor version, then chunks ``[u32 length][tag][payload][u32 CRC-32]``,
all integers little-endian. Floats are float64 by default, so a round trip is
exact; ``float32=True`` halves the size and rounds every coordinate to float32.

The reader trusts nothing: every length is checked against the bytes left
before anything is allocated, every chunk's CRC is checked before its payload
is read, and every fault is an :class:`FdpError` at a byte offset.
"""
from __future__ import annotations

import struct
import zlib
from typing import Any, Callable

import numpy as np

from mpeg4fa.fdp.errors import FdpError
from mpeg4fa.fdp.model import (FAPU_KEYS, LABEL_INDEX, LABELS, TRANSFORM_FIELDS, FaceDefMesh, FaceDefTable,
                               FaceDefTransform, Fdp, FdpMesh, FdpValueError, TextureImage, Where)

MAGIC = b"\x89FDP\r\n\x1a\n"
MAJOR, MINOR = 1, 0
MASK_BYTES = (len(LABELS) + 7) // 8  # 11 bytes for the 84 feature points
_SINGLE = {b"NAME": "name", b"FPTS": "feature_points", b"TXCO": "texture_coords", b"FAPU": "fapu",
           b"MESH": "mesh"}
"""Chunks that may appear at most once, with the part of the model they carry."""
_FLOAT = {4: "<f4", 8: "<f8"}
_F32_MAX = float(np.finfo(np.float32).max)


# ---- writing ----------------------------------------------------------------------------------


def fdp_to_bytes(fdp: Fdp, *, float32: bool = False) -> bytes:
    """The binary stream of ``fdp``; ``float32`` stores coordinates as float32 (exact only to float32)."""
    width = 4 if float32 else 8
    out = [MAGIC, bytes([MAJOR, MINOR])]
    if fdp.name:
        out.append(_chunk(b"NAME", fdp.name.encode("utf-8")))
    if fdp.labels or fdp.texture_coords is not None:  # an empty TXCO needs its (empty) FPTS
        mask = bytearray(MASK_BYTES)
        for label in fdp.labels:
            i = LABEL_INDEX[label]
            mask[i // 8] |= 0x80 >> (i % 8)
        out.append(_chunk(b"FPTS", bytes([width]) + bytes(mask) + _floats(fdp.points, width, "feature points")))
        if fdp.texture_coords is not None:
            out.append(_chunk(b"TXCO", bytes([width]) + _floats(fdp.texture_coords, width, "texture coords")))
    if fdp.fapu is not None:
        present = sum(1 << k for k, key in enumerate(FAPU_KEYS) if key in fdp.fapu)
        values = [fdp.fapu[key] for key in FAPU_KEYS if key in fdp.fapu]
        out.append(_chunk(b"FAPU", bytes([width, present]) + _floats(np.array(values), width, "FAPU")))
    for tex in fdp.textures:
        out.append(_chunk(b"TXIM", _text(tex.name) + _text(tex.media_type) + tex.data))
    if fdp.mesh is not None:
        out.append(_chunk(b"MESH", _mesh_payload(fdp.mesh, width)))
    for table in fdp.tables:
        out.append(_chunk(b"FDTB", _table_payload(table, width)))
    out.append(_chunk(b"IEND", b""))
    data = b"".join(out)
    if float32:  # rounding can break a rule (a tiny FAPU distance or rotation axis becomes 0): check
        try:
            fdp_from_bytes(data)
        except FdpError as exc:
            raise _write_error(f"float32 cannot represent this FDP: {exc.problem}", "write with float32=False") \
                from None
    return data


def _chunk(tag: bytes, payload: bytes) -> bytes:
    if len(payload) > 0xFFFFFFFF:
        raise _write_error(f"chunk {tag.decode()} would hold {len(payload)} bytes; a chunk holds at most 2**32 - 1")
    crc = zlib.crc32(tag + payload)
    return struct.pack("<I", len(payload)) + tag + payload + struct.pack("<I", crc)


def _write_error(problem: str, hint: str = "") -> FdpError:
    return FdpError.no_place("<fdp>", problem, hint)


def _floats(values: np.ndarray, width: int, what: str) -> bytes:
    arr = np.asarray(values, dtype=np.float64)
    if width == 4 and arr.size and float(np.abs(arr).max()) > _F32_MAX:
        raise _write_error(f"{what} hold a value too large for float32", "write with float32=False")
    return arr.astype(_FLOAT[width]).tobytes()


def _text(text: str) -> bytes:
    raw = text.encode("utf-8")
    return struct.pack("<H", len(raw)) + raw  # the model keeps texts within 65535 bytes


def _mesh_payload(mesh: FdpMesh, width: int) -> bytes:
    flags = 1 if mesh.uvs is not None else 0
    parts = [bytes([width, flags]), struct.pack("<II", len(mesh.vertices), len(mesh.triangles)), _text(mesh.name),
             _floats(mesh.vertices, width, "mesh vertices"), mesh.triangles.astype("<u4").tobytes()]
    if mesh.uvs is not None:
        parts.append(_floats(mesh.uvs, width, "mesh uvs"))
    return b"".join(parts)


def _table_payload(table: FaceDefTable, width: int) -> bytes:
    if len(table.meshes) > 0xFFFF or len(table.transforms) > 0xFFFF:
        raise _write_error(f"the table of FAP {table.fap} has more than 65535 meshes or transforms")
    parts = [bytes([width, table.fap, table.high_level_select]),
             struct.pack("<HH", len(table.meshes), len(table.transforms))]
    for fdm in table.meshes:
        parts += [struct.pack("<II", len(fdm.coord_index), len(fdm.interval_borders) - 1),
                  fdm.interval_borders.astype("<i4").tobytes(), fdm.coord_index.astype("<u4").tobytes(),
                  _floats(fdm.displacements, width, "displacements")]
    for tr in table.transforms:
        parts += [bytes([TRANSFORM_FIELDS.index(tr.field)]),
                  _floats(np.concatenate([tr.rotation, tr.scale, tr.translation]), width, "transform")]
    return b"".join(parts)


# ---- reading ----------------------------------------------------------------------------------


class _Payload:
    """A cursor over one chunk's payload that fails with absolute byte offsets."""

    def __init__(self, data: bytes, start: int, end: int, tag: str, path: str) -> None:
        self.data, self.pos, self.end, self.tag, self.path = data, start, end, tag, path

    def fail(self, problem: str, at: int | None = None, hint: str = "") -> FdpError:
        return FdpError.at_byte(self.path, self.pos if at is None else at, f"chunk {self.tag}: {problem}", hint)

    def take(self, n: int, what: str) -> int:
        """Reserve ``n`` bytes for ``what``; return where they start."""
        if n > self.end - self.pos:
            raise self.fail(f"payload too short for {what}: needs {n} bytes, {self.end - self.pos} left")
        at = self.pos
        self.pos += n
        return at

    def u8(self, what: str) -> int:
        return self.data[self.take(1, what)]

    def u16(self, what: str) -> int:
        return int.from_bytes(self.data[self.take(2, what):self.pos], "little")

    def u32(self, what: str) -> int:
        return int.from_bytes(self.data[self.take(4, what):self.pos], "little")

    def width(self) -> int:
        at = self.pos
        width = self.u8("the float width")
        if width not in _FLOAT:
            raise self.fail(f"float width must be 4 or 8, got {width}", at)
        return width

    def array(self, count: int, dtype: str, what: str) -> np.ndarray:
        size = np.dtype(dtype).itemsize
        at = self.take(count * size, f"{count} {what}")
        return np.frombuffer(self.data, dtype=dtype, count=count, offset=at)

    def floats(self, count: int, width: int, what: str) -> np.ndarray:
        raw = self.array(count, _FLOAT[width], what)
        with np.errstate(invalid="ignore"):  # a signalling NaN is rejected later, by the model
            return raw.astype(np.float64)

    def text(self, what: str) -> str:
        n = self.u16(f"the length of {what}")
        at = self.take(n, what)
        try:
            return self.data[at:self.pos].decode("utf-8")
        except UnicodeDecodeError as exc:
            raise self.fail(f"{what} is not valid UTF-8", at + exc.start) from None

    def zero_bits(self, value: int, used: int, at: int, what: str) -> None:
        if value >> used:
            raise self.fail(f"reserved bits of {what} must be 0, got 0x{value:02x}", at)

    def done(self) -> None:
        if self.pos != self.end:
            raise self.fail(f"{self.end - self.pos} unexpected bytes at the end of the payload")


class _Stream:
    """State while reading the chunks of one stream."""

    def __init__(self, data: bytes, path: str) -> None:
        self.data, self.path = data, path
        self.where: dict[Any, int] = {}  # model path head -> chunk offset, to place model errors
        self.parts: dict[str, Any] = {}
        self.textures: list[TextureImage] = []
        self.tables: list[FaceDefTable] = []

    def build(self, at: int, make: Callable[..., Any], *args: Any, **kw: Any) -> Any:
        try:
            return make(*args, **kw)
        except FdpValueError as exc:
            raise FdpError.at_byte(self.path, at, exc.message) from None

    def chunk(self, tag: bytes, p: _Payload, at: int) -> None:
        name = tag.decode("ascii")
        if tag in _SINGLE:
            key = _SINGLE[tag]
            if key in self.where:
                raise p.fail(f"second {name} chunk (the first is at byte {self.where[key]})", at)
            self.where[key] = at
        reader = _READERS.get(tag)
        if reader is not None:
            reader(self, p, at)
            p.done()
        elif name[0].isupper():
            raise p.fail("unknown critical chunk", at, "its tag starts with a capital letter, so it cannot be "
                         "skipped; the stream needs a newer reader")
        # else: ancillary chunk (lower-case first letter) this reader does not know: skipped

    def finish(self) -> Fdp:
        labels, points = self.parts.get("feature_points", ((), np.zeros((0, 3))))
        try:
            return Fdp(labels, points, texture_coords=self.parts.get("texture_coords"),
                       textures=tuple(self.textures), mesh=self.parts.get("mesh"), tables=tuple(self.tables),
                       fapu=self.parts.get("fapu"), name=self.parts.get("name", ""))
        except FdpValueError as exc:
            raise FdpError.at_byte(self.path, self._place(exc.field), exc.message) from None

    def _place(self, where: Where) -> int:
        head = where[0] if where else None
        if head in ("textures", "face_def_tables") and len(where) > 1:
            head = (head, where[1])
        return self.where.get(head, len(MAGIC))


def _read_name(s: _Stream, p: _Payload, at: int) -> None:
    n = p.end - p.pos
    start = p.take(n, "the name")
    try:
        s.parts["name"] = s.data[start:p.pos].decode("utf-8")
    except UnicodeDecodeError as exc:
        raise p.fail("name is not valid UTF-8", start + exc.start) from None


def _read_points(s: _Stream, p: _Payload, at: int) -> None:
    width = p.width()
    mask_at = p.take(MASK_BYTES, "the feature point mask")
    mask = int.from_bytes(s.data[mask_at:p.pos], "big")
    spare = MASK_BYTES * 8 - len(LABELS)
    if mask & ((1 << spare) - 1):
        raise p.fail(f"the last {spare} bits of the feature point mask are reserved and must be 0", p.pos - 1)
    labels = tuple(label for i, label in enumerate(LABELS) if mask >> (MASK_BYTES * 8 - 1 - i) & 1)
    s.parts["feature_points"] = (labels, p.floats(3 * len(labels), width, "point coordinates").reshape(-1, 3))


def _read_texture_coords(s: _Stream, p: _Payload, at: int) -> None:
    if "feature_points" not in s.parts:
        raise p.fail("TXCO before FPTS", at, "texture coordinates follow the feature points they belong to")
    width = p.width()
    n = len(s.parts["feature_points"][0])
    s.parts["texture_coords"] = p.floats(2 * n, width, "texture coordinates").reshape(n, 2)


def _read_fapu(s: _Stream, p: _Payload, at: int) -> None:
    width = p.width()
    mask_at = p.pos
    mask = p.u8("the FAPU mask")
    p.zero_bits(mask, len(FAPU_KEYS), mask_at, "the FAPU mask")
    keys = [key for k, key in enumerate(FAPU_KEYS) if mask >> k & 1]
    values = p.floats(len(keys), width, "FAPU distances")
    s.parts["fapu"] = {key: float(v) for key, v in zip(keys, values)}


def _read_texture(s: _Stream, p: _Payload, at: int) -> None:
    s.where[("textures", len(s.textures))] = at
    name = p.text("the texture name")
    media_type = p.text("the media type")
    start = p.take(p.end - p.pos, "the image")
    s.textures.append(s.build(at, TextureImage, name, media_type, s.data[start:p.pos]))


def _read_mesh(s: _Stream, p: _Payload, at: int) -> None:
    width = p.width()
    flags_at = p.pos
    flags = p.u8("the mesh flags")
    p.zero_bits(flags, 1, flags_at, "the mesh flags")
    n_vertices = p.u32("the vertex count")
    n_triangles = p.u32("the triangle count")
    name = p.text("the mesh name")
    vertices = p.floats(3 * n_vertices, width, "vertex coordinates").reshape(-1, 3)
    triangles = p.array(3 * n_triangles, "<u4", "triangle indices").astype(np.int64).reshape(-1, 3)
    uvs = p.floats(2 * n_vertices, width, "uvs").reshape(-1, 2) if flags & 1 else None
    s.parts["mesh"] = s.build(at, FdpMesh, vertices, triangles, uvs, name)


def _read_table(s: _Stream, p: _Payload, at: int) -> None:
    s.where[("face_def_tables", len(s.tables))] = at
    width = p.width()
    fap, hls = p.u8("the FAP number"), p.u8("high_level_select")
    n_meshes, n_transforms = p.u16("the mesh count"), p.u16("the transform count")
    meshes = []
    for _ in range(n_meshes):
        mesh_at = p.pos
        k, m = p.u32("the vertex count"), p.u32("the interval count")
        borders = p.array(m + 1, "<i4", "interval borders").astype(np.int64)
        index = p.array(k, "<u4", "coord indices").astype(np.int64)
        disp = p.floats(k * m * 3, width, "displacements").reshape(k, m, 3)
        meshes.append(s.build(mesh_at, FaceDefMesh, index, borders, disp))
    transforms = []
    for _ in range(n_transforms):
        tr_at = p.pos
        code = p.u8("the transform field")
        if code >= len(TRANSFORM_FIELDS):
            raise p.fail(f"transform field code must be 0 (rotation), 1 (scale) or 2 (translation), got {code}",
                         tr_at)
        v = p.floats(10, width, "a transform")
        transforms.append(s.build(tr_at, FaceDefTransform, TRANSFORM_FIELDS[code], v[:4], v[4:7], v[7:]))
    s.tables.append(s.build(at, FaceDefTable, fap, hls, tuple(meshes), tuple(transforms)))


def _read_end(s: _Stream, p: _Payload, at: int) -> None:
    """IEND carries nothing; ``done()`` rejects a payload."""


_READERS: dict[bytes, Callable[[_Stream, _Payload, int], None]] = {
    b"NAME": _read_name, b"FPTS": _read_points, b"TXCO": _read_texture_coords, b"FAPU": _read_fapu,
    b"TXIM": _read_texture, b"MESH": _read_mesh, b"FDTB": _read_table, b"IEND": _read_end,
}


def fdp_from_bytes(data: bytes | bytearray | memoryview, path: str = "<bytes>") -> Fdp:
    """Parse a binary FDP stream; any fault is an :class:`FdpError` at a byte offset."""
    data = bytes(data)
    _check_head(data, path)
    stream = _Stream(data, path)
    pos = len(MAGIC) + 2
    while True:
        left = len(data) - pos
        if left == 0:
            raise FdpError.at_byte(path, pos, "stream ends without an IEND chunk", "the file is truncated")
        if left < 12:
            raise FdpError.at_byte(path, pos, f"stream ends inside a chunk header ({left} bytes, a chunk takes "
                                   "at least 12)", "the file is truncated")
        length = int.from_bytes(data[pos:pos + 4], "little")
        tag = data[pos + 4:pos + 8]
        if not all(0x41 <= c <= 0x5A or 0x61 <= c <= 0x7A for c in tag):
            raise FdpError.at_byte(path, pos + 4, f"bad chunk tag {tag!r}: a tag is 4 ASCII letters",
                                   "the stream is damaged or misaligned")
        name = tag.decode("ascii")
        if length > left - 12:
            raise FdpError.at_byte(path, pos, f"chunk {name} declares {length} payload bytes but the stream has "
                                   f"{left - 12} left", "the file is truncated")
        end = pos + 8 + length
        stored = int.from_bytes(data[end:end + 4], "little")
        if zlib.crc32(data[pos + 4:end]) != stored:
            raise FdpError.at_byte(path, pos, f"CRC mismatch in chunk {name}", "the file is damaged")
        stream.chunk(tag, _Payload(data, pos + 8, end, name, path), pos)
        pos = end + 4
        if tag == b"IEND":
            break
    if pos != len(data):
        raise FdpError.at_byte(path, pos, f"{len(data) - pos} bytes after the IEND chunk")
    return stream.finish()


def _check_head(data: bytes, path: str) -> None:
    if data[:len(MAGIC)] != MAGIC:
        if not data:
            raise FdpError.at_byte(path, 0, "empty stream", "a binary FDP starts with an 8-byte magic")
        if MAGIC.startswith(data):
            raise FdpError.at_byte(path, len(data), "stream ends inside the magic", "the file is truncated")
        if data[:4] != MAGIC[:4]:
            raise FdpError.at_byte(path, 0, "not a binary FDP stream (bad magic)",
                                   "a binary FDP starts with the bytes 89 46 44 50 0D 0A 1A 0A")
        bad = next(i for i in range(len(MAGIC)) if i >= len(data) or data[i] != MAGIC[i])
        raise FdpError.at_byte(path, bad, "damaged magic: its line-ending bytes were changed",
                               "the file was probably copied in text mode; copy it as binary")
    if len(data) < len(MAGIC) + 2:
        raise FdpError.at_byte(path, len(data), "stream ends inside the version", "the file is truncated")
    major, minor = data[len(MAGIC)], data[len(MAGIC) + 1]
    if major != MAJOR:
        newer = "newer than" if major > MAJOR else "not supported by"
        raise FdpError.at_byte(path, len(MAGIC), f"FDP stream version {major}.{minor} is {newer} this reader "
                               f"(version {MAJOR}.{MINOR})", "upgrade mpeg4fa" if major > MAJOR else "")
