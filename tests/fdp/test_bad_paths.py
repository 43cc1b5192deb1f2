"""FDP readers given paths and bytes that are not FDP files, absurd counts, unknown encodings: one FdpError naming
the file, bounded memory, no other exception type."""
from __future__ import annotations

import os
import pickle
import struct
import tracemalloc
import zlib
from pathlib import Path

import numpy as np
import pytest

from bad_files import make_cases

from mpeg4fa.errors import MpegFaError
from mpeg4fa.fdp import Fdp, FdpError, FdpValueError, fdp_from_bytes, load_fdp, read_xface_fdp, save_fdp
from mpeg4fa.fdp import errors as fdp_errors
from mpeg4fa.fdp.binary import MAGIC
from mpeg4fa.formats import FormatError

XML = '<xfdp><fdp affects="m" index="1" name="2.1"/></xfdp>'


def _chunk(tag: bytes, payload: bytes) -> bytes:
    return struct.pack("<I", len(payload)) + tag + payload + struct.pack("<I", zlib.crc32(tag + payload))


def _stream(*chunks: bytes) -> bytes:
    return MAGIC + bytes([1, 0]) + b"".join(chunks) + _chunk(b"IEND", b"")


def _cases(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    return make_cases(tmp_path, ".fdp", [
        ("empty.fdp", b"", ""),
        ("utf16.json", '{"format": "mpeg4fa-fdp", "version": 1}'.encode("utf-16"), "UTF-16"),
        ("nul.json", b'{"format": \x00"mpeg4fa-fdp"}', "invalid JSON"),
        ("nul.xml", b"<xfdp>\x00</xfdp>", "invalid XML"),
        ("encoding.fdp", b'<?xml version="1.0" encoding="no-such-enc"?>\n<xfdp/>\n', "no-such-enc"),
        ("truncated.fdp", MAGIC[:5], ""),
    ], seed=3)


@pytest.mark.parametrize("reader", ["load_fdp", "read_xface_fdp"])
def test_every_bad_path_is_one_fdp_error_naming_the_file(tmp_path, reader):
    read = {"load_fdp": load_fdp, "read_xface_fdp": read_xface_fdp}[reader]
    for name, (path, words) in _cases(tmp_path).items():
        with pytest.raises(FdpError) as info:
            read(path)
        err = info.value
        assert err.path == str(path) and str(err).startswith(str(path)), (name, str(err))
        assert isinstance(err, FormatError) and isinstance(err, MpegFaError)
        if reader == "load_fdp" or name in ("missing.fdp", "folder.fdp", "encoding.fdp"):
            assert words in str(err), (name, str(err))


def test_unknown_xml_encoding_is_located_at_its_name(tmp_path):
    """expat asked Python's codecs for the declared encoding: a LookupError escaped before."""
    path = tmp_path / "x.fdp"
    for encoding in ("no-such-enc", "utf-32", "hex", "rot13"):
        path.write_bytes(f'<?xml version="1.0" encoding="{encoding}"?>\n<xfdp/>\n'.encode())
        with pytest.raises(FdpError) as info:
            read_xface_fdp(path)
        assert (info.value.line, info.value.column) == (1, 31), str(info.value)
        assert f"unknown or unsupported XML encoding '{encoding}'" in str(info.value)
        assert "UTF-8" in info.value.hint


def test_utf16_xml_is_still_xml(tmp_path):
    path = tmp_path / "u.fdp"
    path.write_bytes(('<?xml version="1.0"?>' + XML).encode("utf-16"))
    assert read_xface_fdp(path).points == {"2.1": ("m", 1)}
    with pytest.raises(FdpError, match="names mesh vertices"):  # sniffed as Xface through the BOM
        load_fdp(path)


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="no /dev/zero on this system")
def test_a_device_is_refused_before_reading():
    for reader in (load_fdp, read_xface_fdp):
        with pytest.raises(FdpError, match="/dev/zero: is not a regular file"):
            reader("/dev/zero")


def test_an_oversized_file_is_refused_before_reading(tmp_path, monkeypatch):
    monkeypatch.setattr(fdp_errors, "MAX_FILE_BYTES", 100)
    path = tmp_path / "big.fdp"
    path.write_bytes(b"{" + b" " * 200 + b"}")
    with pytest.raises(FdpError, match=r"big\.fdp: is 202 bytes, more than an FDP file may be \(100\)"):
        load_fdp(path)


@pytest.mark.parametrize("payload, words", [
    (bytes([8, 0]) + struct.pack("<II", 2**31, 0) + struct.pack("<H", 0), "6442450944 vertex coordinates"),
    (bytes([8, 0]) + struct.pack("<II", 0, 2**31 - 1) + struct.pack("<H", 0), "triangle indices"),
    (bytes([8, 1]) + struct.pack("<II", 2**32 - 1, 0) + struct.pack("<H", 0), "vertex coordinates"),
])
def test_absurd_mesh_counts_fail_without_allocating(payload, words):
    data = _stream(_chunk(b"MESH", payload))
    tracemalloc.start()
    try:
        with pytest.raises(FdpError) as info:
            fdp_from_bytes(data, "huge.fdp")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20, peak
    assert "payload too short" in str(info.value) and words in str(info.value)
    assert str(info.value).startswith("huge.fdp: byte ")


def test_absurd_table_counts_fail_without_allocating():
    table = bytes([8, 3, 1]) + struct.pack("<HH", 65535, 0) + struct.pack("<II", 2**32 - 1, 2**32 - 1)
    with pytest.raises(FdpError, match="payload too short"):
        fdp_from_bytes(_stream(_chunk(b"FDTB", table)), "t.fdp")


def test_fdp_value_error_is_the_base_error():
    with pytest.raises(FdpValueError) as info:
        Fdp(("2.1", "2.2"), [[0, 0, 0], [0, np.inf, 0]])
    err = info.value
    assert isinstance(err, MpegFaError) and isinstance(err, ValueError)
    assert err.field == ("feature_points", "2.2") and err.where == "feature_points/2.2"
    assert str(err) == f"feature_points/2.2: {err.message}"
    back = pickle.loads(pickle.dumps(err))
    assert (back.message, back.field, back.where, back.key) == (err.message, err.field, err.where, err.key)


def test_fdp_error_where_and_message():
    err = FdpError.at_byte("b.fdp", 12, "bad chunk", "damaged")
    assert (err.where, err.message, err.hint) == ("b.fdp: byte 12", "bad chunk", "damaged")
    assert str(err) == "b.fdp: byte 12: bad chunk (damaged)"
    assert FdpError("x.json", 3, 4, "p").where == "x.json:3:4"
    assert FdpError.no_place("x.json", "p").where == "x.json"


def test_save_to_a_directory_names_it(tmp_path):
    fdp = Fdp.from_points({"2.1": [0, 0, 0]})
    with pytest.raises(FdpError, match="is a directory"):
        save_fdp(fdp, tmp_path)


def test_save_into_no_folder_says_it_cannot_write(tmp_path):
    """Fuzz of 2026-12-07: ``fdp -o /proc/me.fdp`` said "no such file (check the path ...)", a reader's words."""
    fdp = Fdp.from_points({"2.1": [0, 0, 0]})
    with pytest.raises(FdpError) as caught:
        save_fdp(fdp, tmp_path / "no" / "me.fdp")
    assert str(caught.value).startswith(f"{tmp_path / 'no' / 'me.fdp'}: cannot write it")
    assert "existing folder" in caught.value.hint
