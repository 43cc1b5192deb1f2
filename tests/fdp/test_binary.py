"""The binary FDP stream: round trips, the layout of spec/FDP_STREAM.md, and faults at byte offsets."""
from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mpeg4fa.fdp import (FaceDefMesh, FaceDefTable, FaceDefTransform, Fdp, FdpError, FdpMesh, TextureImage,
                         fdp_from_bytes, fdp_from_json, fdp_to_bytes, fdp_to_json)
from mpeg4fa.fdp.binary import MAGIC
from mpeg4fa.fdp.model import LABELS

HEAD = MAGIC + b"\x01\x00"


def full_fdp() -> Fdp:
    rng = np.random.default_rng(11)
    mesh = FdpMesh(rng.normal(size=(6, 3)), [[0, 1, 2], [2, 3, 4], [4, 5, 0]], uvs=rng.random((6, 2)), name="skin")
    tables = (
        FaceDefTable(3, 1, (FaceDefMesh([0, 5], [-200, 0, 300], rng.normal(size=(2, 2, 3))),
                            FaceDefMesh([1], [0, 1000], rng.normal(size=(1, 1, 3)))),
                     (FaceDefTransform("rotation", rotation=[1, 0, 0, 1e-5]),)),
        FaceDefTable(2, 7, (), (FaceDefTransform("scale", scale=[1.1, 1, 1]),
                                FaceDefTransform("translation", translation=[0, 0.5, 0]))),
        FaceDefTable(48),
    )
    points = {label: rng.normal(size=3) for label in ("2.1", "2.14", "3.1", "7.1", "9.15", "11.6")}
    return Fdp.from_points(points, texture_coords={label: rng.random(2) for label in points},
                           textures=(TextureImage("skin", "image/png", bytes(range(256)) * 3),
                                     TextureImage("é", "image/jpeg", b"")),
                           mesh=mesh, tables=tables, fapu={"ES0": 69.5, "MW0": 50}, name="Zoë")


def chunk(tag: bytes, payload: bytes) -> bytes:
    return struct.pack("<I", len(payload)) + tag + payload + struct.pack("<I", zlib.crc32(tag + payload))


IEND = chunk(b"IEND", b"")


def error(data: bytes) -> FdpError:
    with pytest.raises(FdpError) as info:
        fdp_from_bytes(data, "face.fdp")
    assert info.value.line is None and info.value.column is None
    assert str(info.value).startswith(f"face.fdp: byte {info.value.offset}: ")
    return info.value


def chunks(data: bytes) -> list[tuple[int, bytes, bytes]]:
    """(offset, tag, payload) of each chunk of a well-formed stream."""
    out, pos = [], len(HEAD)
    while pos < len(data):
        length = int.from_bytes(data[pos:pos + 4], "little")
        out.append((pos, data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]))
        pos += 12 + length
    return out


def float32_rounded(fdp: Fdp) -> Fdp:
    """What a float32 stream of ``fdp`` reads back as."""
    r = lambda a: None if a is None else np.asarray(a, np.float32).astype(np.float64)  # noqa: E731
    mesh = fdp.mesh and FdpMesh(r(fdp.mesh.vertices), fdp.mesh.triangles, r(fdp.mesh.uvs), fdp.mesh.name)
    tables = tuple(FaceDefTable(t.fap, t.high_level_select,
                                tuple(FaceDefMesh(m.coord_index, m.interval_borders, r(m.displacements))
                                      for m in t.meshes),
                                tuple(FaceDefTransform(x.field, r(x.rotation), r(x.scale), r(x.translation))
                                      for x in t.transforms)) for t in fdp.tables)
    fapu = None if fdp.fapu is None else {k: float(np.float32(v)) for k, v in fdp.fapu.items()}
    return Fdp(fdp.labels, r(fdp.points), r(fdp.texture_coords), fdp.textures, mesh, tables, fapu, fdp.name)


# ---- round trips -------------------------------------------------------------------------------------


def test_full_round_trip_is_exact():
    fdp = full_fdp()
    assert fdp_from_bytes(fdp_to_bytes(fdp)) == fdp


@pytest.mark.parametrize("fdp", [
    Fdp((), []),
    Fdp.from_points({"2.1": [1, 2, 3]}),
    Fdp.from_points({"7.1": [0, 0, 0]}, fapu={}),
    Fdp.from_points({label: [i, -i, 0.5 * i] for i, label in enumerate(
        ["2.1", "2.2", "3.14", "4.1", "8.10", "9.1", "11.5", "11.6"])}),
    Fdp((), [], mesh=FdpMesh(np.zeros((0, 3)), np.zeros((0, 3), int))),
    Fdp((), [], mesh=FdpMesh(np.zeros((3, 3)), [[0, 1, 2]])),
    Fdp((), [], tables=(FaceDefTable(2, 64),), name="only a table"),
    Fdp((), [], texture_coords=np.zeros((0, 2))),
])
def test_round_trip_of_optional_parts(fdp):
    assert fdp_from_bytes(fdp_to_bytes(fdp)) == fdp


finite = st.floats(allow_nan=False, allow_infinity=False)
unit = st.floats(0, 1)


@st.composite
def fdps(draw) -> Fdp:
    """Random FDPs: any subset of points, any finite floats, each optional part present or not."""
    labels = draw(st.lists(st.sampled_from(LABELS), unique=True, max_size=12))
    points = {label: draw(st.lists(finite, min_size=3, max_size=3)) for label in labels}
    uv = {label: draw(st.lists(unit, min_size=2, max_size=2)) for label in labels} if draw(st.booleans()) else None
    n = draw(st.integers(1, 4))
    mesh = FdpMesh(draw(st.lists(st.lists(finite, min_size=3, max_size=3), min_size=n, max_size=n)),
                   draw(st.lists(st.lists(st.integers(0, n - 1), min_size=3, max_size=3), max_size=3)),
                   name=draw(st.text(max_size=4))) if draw(st.booleans()) else None
    tables = []
    for fap in draw(st.lists(st.integers(1, 68), unique=True, max_size=3)):
        meshes = ()
        if mesh is not None and draw(st.booleans()):
            borders = sorted(draw(st.sets(st.integers(-2**31, 2**31 - 1), min_size=2, max_size=4)))
            k = draw(st.integers(0, n))
            disp = draw(st.lists(finite, min_size=k * (len(borders) - 1) * 3, max_size=k * (len(borders) - 1) * 3))
            meshes = (FaceDefMesh(list(range(k)), borders, np.reshape(disp, (k, len(borders) - 1, 3))),)
        transforms = tuple(FaceDefTransform(field, translation=draw(st.lists(finite, min_size=3, max_size=3)))
                           for field in draw(st.lists(st.sampled_from(["rotation", "scale", "translation"]),
                                                      max_size=2)))
        tables.append(FaceDefTable(fap, draw(st.integers(1, 64)), meshes, transforms))
    fapu = draw(st.none() | st.dictionaries(st.sampled_from(["IRISD0", "ES0", "ENS0", "MNS0", "MW0"]),
                                            st.floats(min_value=1e-300, allow_infinity=False)))
    textures = tuple(TextureImage(draw(st.text(max_size=3)), "image/png", draw(st.binary(max_size=8)))
                     for _ in range(draw(st.integers(0, 2))))
    return Fdp.from_points(points, texture_coords=uv, textures=textures, mesh=mesh, tables=tuple(tables),
                           fapu=fapu, name=draw(st.text(max_size=5)))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(fdps())
def test_random_fdps_round_trip_in_both_forms(fdp):
    assert fdp_from_bytes(fdp_to_bytes(fdp)) == fdp
    assert fdp_from_json(fdp_to_json(fdp)) == fdp


def test_every_single_point_round_trips_through_the_mask():
    rng = np.random.default_rng(1)
    full = Fdp.from_points({label: rng.normal(size=3) for label in LABELS})
    assert fdp_from_bytes(fdp_to_bytes(full)) == full
    for label in full.labels:
        sub = full.subset([label])
        assert fdp_from_bytes(fdp_to_bytes(sub)) == sub


def test_float32_streams_are_smaller_and_exact_to_float32():
    fdp = full_fdp()
    small, big = fdp_to_bytes(fdp, float32=True), fdp_to_bytes(fdp)
    assert len(small) < len(big)
    back = fdp_from_bytes(small)
    assert back != fdp
    assert back == float32_rounded(fdp)


def test_float32_refuses_values_it_cannot_hold():
    fdp = Fdp.from_points({"2.1": [1e300, 0, 0]})
    with pytest.raises(FdpError, match="too large for float32"):
        fdp_to_bytes(fdp, float32=True)
    assert fdp_from_bytes(fdp_to_bytes(fdp)) == fdp
    with pytest.raises(FdpError, match="float32 cannot represent this FDP: FAPU distance ES0 must be a positive"):
        fdp_to_bytes(Fdp((), [], fapu={"ES0": 1e-300}), float32=True)


# ---- the documented layout ------------------------------------------------------------------------


def test_the_example_of_the_spec_byte_for_byte():
    data = fdp_to_bytes(Fdp.from_points({"2.1": [0, 1, 2]}, name="a"), float32=True)
    name = chunk(b"NAME", b"a")
    points = chunk(b"FPTS", bytes.fromhex("04" "80000000000000000000 00".replace(" ", ""))
                   + bytes.fromhex("00000000 0000803F 00000040".replace(" ", "")))
    assert data == HEAD + name + points + IEND
    assert IEND == bytes.fromhex("00000000 49454E44 826042AE".replace(" ", ""))  # CRC 0xAE426082, little-endian
    assert MAGIC == bytes.fromhex("89 46 44 50 0D 0A 1A 0A".replace(" ", ""))


def test_mask_bit_order():
    data = fdp_to_bytes(Fdp.from_points({"2.1": [0, 0, 0], "3.14": [0, 0, 0], "11.6": [0, 0, 0]}))
    (payload,) = [payload for _, tag, payload in chunks(data) if tag == b"FPTS"]
    assert payload[1:12] == bytes.fromhex("80 00 00 10 00 00 00 00 00 00 10".replace(" ", ""))


def test_chunk_order_written():
    tags = [tag for _, tag, _ in chunks(fdp_to_bytes(full_fdp()))]
    assert tags == [b"NAME", b"FPTS", b"TXCO", b"FAPU", b"TXIM", b"TXIM", b"MESH", b"FDTB", b"FDTB", b"FDTB", b"IEND"]


def test_fapu_mask_and_field_codes():
    data = fdp_to_bytes(Fdp((), [], fapu={"IRISD0": 1, "MW0": 2},
                            tables=(FaceDefTable(9, 1, (), (FaceDefTransform("translation"),)),)))
    parts = {tag: payload for _, tag, payload in chunks(data)}
    assert parts[b"FAPU"][:2] == bytes([8, 0b10001])
    assert struct.unpack("<2d", parts[b"FAPU"][2:]) == (1.0, 2.0)
    assert parts[b"FDTB"][:7] == bytes([8, 9, 1, 0, 0, 1, 0]) and parts[b"FDTB"][7] == 2


# ---- chunk-level rules ----------------------------------------------------------------------------------


def test_unknown_ancillary_chunk_is_skipped_and_critical_one_rejected():
    good = fdp_to_bytes(Fdp.from_points({"2.1": [1, 2, 3]}))
    extra = chunk(b"zzTp", b"anything at all")
    assert fdp_from_bytes(good[:len(HEAD)] + extra + good[len(HEAD):]) == fdp_from_bytes(good)
    err = error(good[:len(HEAD)] + chunk(b"ZZTP", b"") + good[len(HEAD):])
    assert err.offset == len(HEAD) and "unknown critical chunk" in err.problem and "ZZTP" in err.problem


def test_versions():
    good = fdp_to_bytes(Fdp.from_points({"2.1": [1, 2, 3]}))
    assert fdp_from_bytes(good[:9] + b"\x07" + good[10:]) == fdp_from_bytes(good)  # newer minor: fine
    err = error(good[:8] + b"\x02\x03" + good[10:])
    assert err.offset == 8 and "2.3" in err.problem and "1.0" in err.problem and "newer" in err.problem
    err = error(good[:8] + b"\x00\x09" + good[10:])
    assert "0.9" in err.problem and "not supported" in err.problem


@pytest.mark.parametrize("data, offset, message", [
    (b"", 0, "empty stream"),
    (b"\x89FDP\r", 5, "ends inside the magic"),
    (b"PK\x03\x04 zip", 0, "bad magic"),
    (b"\x89FDP\n\x1a\n\x01\x00", 4, "line-ending"),  # \r\n became \n
    (HEAD[:9], 9, "ends inside the version"),
    (HEAD, 10, "without an IEND"),
    (HEAD + IEND[:7], 10, "inside a chunk header"),
    (HEAD + b"\x00\x00\x00\x00IE1D\x00\x00\x00\x00", 14, "bad chunk tag"),
    (HEAD + struct.pack("<I", 100) + b"NAMEabcdefgh", 10, "declares 100 payload bytes but the stream has 4 left"),
    (HEAD + IEND + b"\x00", 22, "1 bytes after the IEND"),
    (HEAD + chunk(b"IEND", b"x"), 18, "1 unexpected bytes at the end"),
])
def test_framing_faults(data, offset, message):
    err = error(data)
    assert err.offset == offset and message in err.problem


def test_crc_mismatch_names_the_chunk_and_its_offset():
    data = bytearray(fdp_to_bytes(full_fdp()))
    at, tag, payload = chunks(bytes(data))[3]
    data[at + 8 + len(payload) // 2] ^= 0x01
    err = error(bytes(data))
    assert err.offset == at and f"CRC mismatch in chunk {tag.decode()}" in err.problem


@pytest.mark.parametrize("body, offset, message", [
    (chunk(b"NAME", b"a") + chunk(b"NAME", b"b"), 23, "second NAME chunk (the first is at byte 10)"),
    (chunk(b"TXCO", b"\x08"), 10, "TXCO before FPTS"),
    (chunk(b"FPTS", b"\x05" + bytes(11)), 18, "float width must be 4 or 8, got 5"),
    (chunk(b"FPTS", b"\x08" + bytes(10) + b"\x01"), 29, "reserved and must be 0"),
    (chunk(b"FPTS", b"\x08\x80" + bytes(10) + bytes(16)), 30, "needs 24 bytes, 16 left"),
    (chunk(b"FAPU", b"\x08\x20"), 19, "reserved bits of the FAPU mask"),
    (chunk(b"FAPU", b"\x08\x01" + struct.pack("<d", -2)), 10, "positive"),
    (chunk(b"MESH", b"\x08\x02" + bytes(10)), 19, "reserved bits of the mesh flags"),
    (chunk(b"MESH", b"\x08\x00" + struct.pack("<II", 0xFFFFFFFF, 0) + b"\x00\x00"), 30, "needs 103079215080 bytes"),
    (chunk(b"MESH", b"\x08\x00" + struct.pack("<II", 1, 1) + b"\x00\x00" + bytes(24) + struct.pack("<3I", 0, 0, 1)),
     10, "must lie in [0, 0], got 1"),
    (chunk(b"TXIM", b"\x01\x00\xff\x09\x00image/png"), 20, "texture name is not valid UTF-8"),
    (chunk(b"TXIM", b"\x00\x00\x03\x00png"), 10, "type/subtype"),
    (chunk(b"FDTB", b"\x08\x45\x01\x00\x00\x00\x00"), 10, "fap must lie in 1..68, got 69"),
    (chunk(b"FDTB", b"\x08\x03\x01\x00\x00\x01\x00\x07" + bytes(80)), 25, "transform field code"),
    (chunk(b"FDTB", b"\x08\x03\x01\x01\x00\x00\x00" + struct.pack("<II", 0, 1) + struct.pack("<ii", 5, 5)), 25,
     "strictly increasing"),
    (chunk(b"FDTB", b"\x08\x03\x01\x01\x00\x00\x00" + struct.pack("<II", 1, 1) + struct.pack("<iiI", 0, 5, 0)
           + bytes(24)), 10, "needs the FDP's mesh"),
    (chunk(b"FDTB", b"\x08\x03\x01\x00\x00\x00\x00") + chunk(b"FDTB", b"\x08\x03\x01\x00\x00\x00\x00"), 29,
     "already has a table"),
    (chunk(b"FPTS", b"\x08\x80" + bytes(10) + struct.pack("<3d", 0, float("nan"), 0)), 10, "finite"),
    (chunk(b"FPTS", b"\x04\x80" + bytes(10) + bytes.fromhex("00000000 0100807F 00000000".replace(" ", ""))), 10,
     "finite"),  # a float32 signalling NaN
    (chunk(b"FPTS", b"\x08\x80" + bytes(10) + bytes(24)) + chunk(b"TXCO", b"\x08" + struct.pack("<2d", 0, 3)), 58,
     "must lie in [0, 1]"),
])
@pytest.mark.filterwarnings("error")
def test_payload_faults_have_the_offset_of_the_field_or_chunk(body, offset, message):
    err = error(HEAD + body + IEND)
    assert message in err.problem, str(err)
    assert err.offset == offset, str(err)
