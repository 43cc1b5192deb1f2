"""FDP JSON and points files go through the package's JSON reader: deep nesting, bad bytes and
foreign files are one located FdpError, found before parsing (issue 26 item 4)."""
from __future__ import annotations

import pytest

from mpeg4fa.fdp import FdpError, load_fdp, read_points_json
from mpeg4fa.fdp.json_form import fdp_from_json


@pytest.mark.parametrize("data, place, words", [
    (b"[" * 100_000, (1, 17), "nested more than 16 levels"),
    (b'{"3.5": [1, 2],\n "2.1": [1, "\xff"]}', (2, 14), "not UTF-8: byte 0xff"),
    (b'{"3.5": [1, 2],\n "2.1": [1, NaN]}', (2, 13), "NaN is not a number"),
    (b"\xff\xd8\xff\xe0" + bytes(40), (None, None), "(a JPEG image)"),
])
def test_points_file_damage_is_located(tmp_path, data, place, words):
    path = tmp_path / "points.json"
    path.write_bytes(data)
    with pytest.raises(FdpError) as info:
        read_points_json(path)
    assert (info.value.line, info.value.column) == place and words in str(info.value)


def test_deep_fdp_json_is_refused_before_parsing(tmp_path):
    text = '{"format": "mpeg4fa-fdp", "version": 1, "name": ' + "[" * 100_000
    with pytest.raises(FdpError, match="nested more than 16 levels") as info:
        fdp_from_json(text, "deep.json")
    assert (info.value.line, info.value.column) == (1, 64)  # the 16th '[' is the 17th level
    path = tmp_path / "deep.json"
    path.write_text(text)
    with pytest.raises(FdpError, match="nested"):
        load_fdp(path)


@pytest.mark.parametrize("data, words", [
    (b"\xff\xd8\xff\xe0" + bytes(40), "starts with 0xFFD8FFE0 (a JPEG image)"),
    (b"\x00\x00\x01\xba" + bytes(40), "(an FBA stream)"),
    (b"RIFF\x00\x00\x00\x00WAVEfmt ", "(a WAV audio file)"),
])
def test_a_foreign_file_given_as_fdp_is_named(tmp_path, data, words):
    path = tmp_path / "face.fdp"
    path.write_bytes(data)
    with pytest.raises(FdpError, match="not an FDP file") as info:
        load_fdp(path)
    assert words in str(info.value) and str(info.value).startswith(f"{path}: byte 0")
