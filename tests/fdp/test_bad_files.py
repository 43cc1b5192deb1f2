"""Damaged and hostile input in every form: only FdpError (or a clean read), never a hang or another exception;
and load_fdp/save_fdp on real files."""
from __future__ import annotations

import json
import struct
import zlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mpeg4fa.fdp import (FaceDefMesh, FaceDefTable, FaceDefTransform, Fdp, FdpError, FdpMesh, TextureImage,
                         fdp_from_bytes, fdp_from_json, fdp_to_bytes, fdp_to_json, load_fdp, save_fdp, sniff_fdp,
                         xface_from_xml)
from mpeg4fa.fdp.binary import MAGIC

FUZZ = settings(max_examples=150, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])


def small_fdp() -> Fdp:
    """Every part present, as small as possible (~450 bytes as float32)."""
    mesh = FdpMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], uvs=[[0, 0], [1, 0], [0, 1]], name="m")
    table = FaceDefTable(3, 1, (FaceDefMesh([2], [-1, 0, 1], [[[0, 1, 0], [0, 2, 0]]]),),
                         (FaceDefTransform("translation", translation=[0, 1, 0]),))
    return Fdp.from_points({"2.1": [0, -1, 0.5], "11.4": [0, 1, 0]}, texture_coords={"2.1": [0.5, 0], "11.4": [0.5, 1]},
                           textures=(TextureImage("t", "image/png", b"PNG"),), mesh=mesh, tables=(table,),
                           fapu={"ES0": 1.5}, name="s")


SMALL = fdp_to_bytes(small_fdp(), float32=True)
SMALL_JSON = fdp_to_json(small_fdp())
XML = """<xfdp><head><fapu ES0="2" MW0="3"/><translation x="1" y="2" z="3"/></head>
<source><entity alias="a" category="b"><mesh file="f.wrl" format="wrl"/></entity></source>
<fdp affects="m" index="1" name="2.1"><indices>0 1 2</indices><influence fap="2" type="T" weight="0.5"/></fdp>
</xfdp>"""


def read_binary_or_fdp_error(data: bytes) -> Fdp | FdpError:
    try:
        return fdp_from_bytes(data, "x.fdp")
    except FdpError as err:
        assert err.offset is not None and 0 <= err.offset <= len(data), str(err)
        return err


def with_fixed_crcs(data: bytes) -> bytes:
    """Recompute every chunk CRC (where the framing still parses) so damage reaches the payload readers."""
    out, pos = bytearray(data), len(MAGIC) + 2
    while pos + 12 <= len(out):
        length = int.from_bytes(out[pos:pos + 4], "little")
        end = pos + 8 + length
        if end + 4 > len(out):
            break
        out[end:end + 4] = struct.pack("<I", zlib.crc32(bytes(out[pos + 4:end])))
        pos = end + 4
    return bytes(out)


# ---- binary -------------------------------------------------------------------------------------------


def test_small_stream_is_small_and_reads():
    assert len(SMALL) < 600
    assert fdp_from_bytes(fdp_to_bytes(small_fdp())) == small_fdp()


def test_truncation_at_every_byte():
    for n in range(len(SMALL)):
        result = read_binary_or_fdp_error(SMALL[:n])
        assert isinstance(result, FdpError), n


def test_single_byte_corruption_at_every_byte():
    for i in range(len(SMALL)):
        for flip in (0x01, 0x80, 0xFF):
            data = bytearray(SMALL)
            data[i] ^= flip
            read_binary_or_fdp_error(bytes(data))


def test_payload_corruption_behind_valid_crcs():
    for i in range(len(MAGIC) + 2, len(SMALL)):
        for value in (0x00, 0x7F, 0xFF):
            data = bytearray(SMALL)
            data[i] = value
            read_binary_or_fdp_error(with_fixed_crcs(bytes(data)))


@FUZZ
@given(st.binary(max_size=300))
def test_random_bytes(data):
    read_binary_or_fdp_error(data)
    read_binary_or_fdp_error(MAGIC + b"\x01\x00" + data)


@FUZZ
@given(st.lists(st.tuples(st.sampled_from([b"NAME", b"FPTS", b"TXCO", b"FAPU", b"TXIM", b"MESH", b"FDTB",
                                           b"IEND", b"abcd"]),
                          st.binary(max_size=80)), max_size=6))
def test_random_chunks_with_valid_framing(parts):
    body = b"".join(struct.pack("<I", len(p)) + t + p + struct.pack("<I", zlib.crc32(t + p)) for t, p in parts)
    read_binary_or_fdp_error(MAGIC + b"\x01\x00" + body)


@FUZZ
@given(st.data())
def test_mutated_payload_fields(data):
    blob = bytearray(fdp_to_bytes(small_fdp()))
    for _ in range(data.draw(st.integers(1, 4))):
        blob[data.draw(st.integers(len(MAGIC) + 2, len(blob) - 1))] = data.draw(st.integers(0, 255))
    read_binary_or_fdp_error(with_fixed_crcs(bytes(blob)))


# ---- JSON ------------------------------------------------------------------------------------------------


def read_json_or_fdp_error(text: str | bytes) -> Fdp | FdpError:
    try:
        return fdp_from_json(text, "x.json")
    except FdpError as err:
        assert err.line is not None and err.line >= 1 and err.column is not None and err.column >= 1, str(err)
        return err


def test_json_truncated_at_every_character():
    for n in range(0, len(SMALL_JSON) - 2):
        assert isinstance(read_json_or_fdp_error(SMALL_JSON[:n]), FdpError)


json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2**70, 2**70) | st.floats(allow_nan=True) | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=5), inner, max_size=4),
    max_leaves=12)


@FUZZ
@given(st.data())
def test_json_with_a_part_replaced_by_random_json(data):
    doc = json.loads(SMALL_JSON)
    node, path = doc, []
    while isinstance(node, (dict, list)) and node and data.draw(st.booleans()):
        key = data.draw(st.sampled_from(sorted(node) if isinstance(node, dict) else list(range(len(node)))))
        path.append(key)
        node = node[key]
    if not path:
        return
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = data.draw(json_values)
    read_json_or_fdp_error(json.dumps(doc, indent=data.draw(st.sampled_from([None, 1]))))


@FUZZ
@given(st.text(max_size=200))
def test_json_random_text(text):
    read_json_or_fdp_error(text)
    read_json_or_fdp_error(text.encode("utf-8", "surrogatepass"))


# ---- Xface XML ------------------------------------------------------------------------------------------


def read_xml_or_fdp_error(data: str | bytes) -> object:
    try:
        return xface_from_xml(data, "x.fdp")
    except FdpError as err:
        assert err.line is not None and err.line >= 1 and err.column is not None and err.column >= 1, str(err)
        return err


def test_xml_truncated_at_every_byte():
    raw = XML.encode()
    assert not isinstance(read_xml_or_fdp_error(raw), FdpError)
    for n in range(len(raw)):
        read_xml_or_fdp_error(raw[:n])


@FUZZ
@given(st.binary(max_size=200))
def test_xml_random_bytes(data):
    read_xml_or_fdp_error(b"<xfdp>" + data)
    read_xml_or_fdp_error(data)


@FUZZ
@given(st.integers(0, len(XML) - 1), st.text(max_size=3))
def test_xml_with_a_character_replaced(at, text):
    read_xml_or_fdp_error(XML[:at] + text + XML[at + 1:])


# ---- load_fdp / save_fdp ---------------------------------------------------------------------------------


def test_save_and_load_by_content(tmp_path):
    fdp = small_fdp()
    save_fdp(fdp, tmp_path / "a.fdp")
    save_fdp(fdp, tmp_path / "a.JSON")
    assert (tmp_path / "a.fdp").read_bytes().startswith(MAGIC)
    assert (tmp_path / "a.JSON").read_text(encoding="utf-8").startswith("{")
    assert load_fdp(tmp_path / "a.fdp") == fdp
    assert load_fdp(tmp_path / "a.JSON") == fdp
    (tmp_path / "a.fdp").rename(tmp_path / "binary.json")  # the name lies; content decides
    assert load_fdp(str(tmp_path / "binary.json")) == fdp
    save_fdp(fdp, tmp_path / "f32.fdp", float32=True)
    assert load_fdp(tmp_path / "f32.fdp").labels == fdp.labels


def test_load_xface_needs_meshes(tmp_path):
    path = tmp_path / "x.fdp"
    path.write_text("\ufeff\n  " + XML, encoding="utf-8")
    with pytest.raises(FdpError, match="names mesh vertices") as info:
        load_fdp(path)
    assert "read_xface_fdp" in info.value.hint
    fdp = load_fdp(path, meshes={"m": [[0, 0, 0], [1, 2, 3]]})
    np.testing.assert_array_equal(fdp.point("2.1"), [1, 2, 3])
    assert fdp.fapu == {"ES0": 2.0, "MW0": 3.0}


@pytest.mark.parametrize("content, message", [
    (b"", "the file is empty"),
    (b"hello", "not an FDP file"),
    (b"\x89PNG\r\n\x1a\n", "not an FDP file"),
])
def test_load_unrecognised_content(tmp_path, content, message):
    path = tmp_path / "x.fdp"
    path.write_bytes(content)
    with pytest.raises(FdpError, match=message) as info:
        load_fdp(path)
    assert str(info.value).startswith(str(path))


def test_load_errors_carry_the_path_and_place(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text('{"format": "mpeg4fa-fdp",\n "version": 1,\n "feature_points": {"99.1": [0, 0, 0]}}')
    with pytest.raises(FdpError) as info:
        load_fdp(path)
    assert str(info.value).startswith(f"{path}:3:21: unknown feature point label '99.1'")
    path = tmp_path / "bad.fdp"
    path.write_bytes(SMALL[:-3])
    with pytest.raises(FdpError, match=r"bad\.fdp: byte \d+: "):
        load_fdp(path)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(FdpError) as info:
        load_fdp(tmp_path / "nope.fdp")
    assert info.value.problem == "no such file" and info.value.hint
    assert info.value.line is None and info.value.offset is None
    with pytest.raises(FdpError, match="directory"):
        load_fdp(tmp_path)
    with pytest.raises(FdpError, match="cannot write it: no such folder"):  # an output's words, not a reader's
        save_fdp(small_fdp(), tmp_path / "missing-dir" / "a.fdp")


def test_sniff():
    assert sniff_fdp(SMALL) == "binary"
    assert sniff_fdp(b"\x89FDP\n\x1a\n") == "binary"  # mangled magic still goes to the binary reader
    assert sniff_fdp(b"  \n{") == "json"
    assert sniff_fdp(b"\xef\xbb\xbf<?xml") == "xface"
    assert sniff_fdp(b"x") is None
