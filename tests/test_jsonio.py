"""The one JSON reader (mpeg4fa.jsonio): every hostile document is one located error, in linear time."""
from __future__ import annotations

import pytest

from mpeg4fa.errors import MpegFaError
from mpeg4fa.formats import FormatError
from mpeg4fa.jsonio import JsonError, LineIndex, line_col, loads, read_json


@pytest.mark.parametrize("data, words, place", [
    (b"[" * 100_000, "nested more than 64 levels", (1, 65)),
    (b'{"a": "[[[[", "b": ' + b"[" * 70, "nested more than 64", (1, 83)),
    (b'{"a":\n NaN}', "NaN is not a number", (2, 2)),
    (b'[1,\n -Infinity]', "-Infinity is not a number", (2, 2)),
    (b'{"x": "1e999",\n "a": 1e999}', "beyond what a double holds", (2, 7)),
    (b"[" + b"7" * 5000 + b"]", "5,000 digits", (1, 2)),
    (b'{"a":\n "caf\xe9"}', "not UTF-8: byte 0xe9", (2, 6)),
    (b"\xff\xfe[\x00]\x00", "UTF-16", (1, 1)),
    (b'{"a": [1, 2}', "invalid JSON", (1, 12)),
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "starts with 0x89504E47 (a PNG image)", (None, None)),
    (b"PK\x03\x04rest", "ZIP archive", (None, None)),
])
def test_hostile_documents_are_located(data, words, place):
    with pytest.raises(JsonError) as info:
        loads(data, "f.json")
    assert words in str(info.value) and (info.value.line, info.value.column) == place
    assert str(info.value).startswith("f.json")
    assert isinstance(info.value, MpegFaError)


def test_brackets_inside_strings_do_not_count():
    assert loads(b'{"a": "' + b"[" * 1000 + b'\\"' + b"{" * 1000 + b'"}') == {"a": "[" * 1000 + '"' + "{" * 1000}


def test_size_cap_and_callers_error_type(tmp_path):
    path = tmp_path / "big.json"
    path.write_bytes(b"[" + b"0," * 600 + b"0]")
    with pytest.raises(FormatError, match="larger than the 1,000 bytes"):
        read_json(path, max_bytes=1000, error=FormatError)
    with pytest.raises(FormatError, match="no such file"):
        read_json(tmp_path / "missing.json", error=FormatError)
    with pytest.raises(FormatError, match="is a directory"):
        read_json(tmp_path, error=FormatError)


def test_a_deep_megabyte_is_refused_before_parsing():
    with pytest.raises(JsonError, match="nested more than 8 levels") as info:
        loads(b"[" * 1_000_000 + b"]" * 1_000_000, max_depth=8)
    assert info.value.column == 9


def test_line_index_agrees_with_counting():
    text = "a\nbb\n\nccc\n"
    index = LineIndex(text)
    for offset in range(len(text)):
        assert index.line_col(offset) == line_col(text, offset)


def test_an_unterminated_string_of_escaped_quotes_is_one_pass():
    # each escaped quote used to start a new scan to the end of the text: quadratic (40,000: 36 s)
    with pytest.raises(JsonError, match="Unterminated string") as info:
        loads('["' + '\\"' * 200_000)
    assert (info.value.line, info.value.column) == (1, 2)
